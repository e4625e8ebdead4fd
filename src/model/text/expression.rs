//! One expression of a text model: its parser, its tape and what it reveals about L.
//!
//! [`Expression::parse`] reads the grammar of the [module docs](crate::model::text) by
//! recursive descent (one function per precedence level: precedence climbing written out),
//! folds constant subexpressions, and emits a postfix tape: one [`Op`] per node, evaluated by
//! [`Expression::evaluate`] on a fixed-size array (no allocation per evaluation), generic over
//! [`Scalar`].

use crate::model::text::TextError;
use crate::scalar::Scalar;

/// Most values an expression's tape keeps on its stack at once; deeper expressions are an
/// error ([`TextError::TooDeep`]). A sum or product of any length needs two slots; only
/// nesting to the right (`a*(b*(c*...))`) needs more.
pub const MAX_STACK: usize = 64;

/// Most numbers, names and operations in one expression (it bounds the recursion of the
/// folding and analysis over the tree, whatever the input).
pub const MAX_NODES: usize = 2048;

/// Most nested parentheses, function calls, unary signs and powers inside one another (it
/// bounds the parser's recursion, whatever the input).
const MAX_NESTING: usize = 200;

/// The functions of the grammar, by name.
pub const FUNCTION_NAMES: &[&str] = &[
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "ln",
    "log", "sqrt", "abs",
];

/// The named constants of the grammar.
pub const CONSTANT_NAMES: &[&str] = &["pi", "e"];

/// A function of one argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Function {
    Sin,
    Cos,
    Tan,
    Asin,
    Acos,
    Atan,
    Sinh,
    Cosh,
    Tanh,
    Exp,
    Ln,
    Sqrt,
    Abs,
}

impl Function {
    /// The function named `name` (`log` is the natural logarithm, as `ln`); `atan2` takes two
    /// arguments and is not one of these.
    fn named(name: &str) -> Option<Function> {
        Some(match name {
            "sin" => Function::Sin,
            "cos" => Function::Cos,
            "tan" => Function::Tan,
            "asin" => Function::Asin,
            "acos" => Function::Acos,
            "atan" => Function::Atan,
            "sinh" => Function::Sinh,
            "cosh" => Function::Cosh,
            "tanh" => Function::Tanh,
            "exp" => Function::Exp,
            "ln" | "log" => Function::Ln,
            "sqrt" => Function::Sqrt,
            "abs" => Function::Abs,
            _ => return None,
        })
    }

    /// The function at `x`, in any scalar type.
    #[inline]
    fn apply<D: Scalar>(self, x: D) -> D {
        match self {
            Function::Sin => x.sin(),
            Function::Cos => x.cos(),
            Function::Tan => x.tan(),
            Function::Asin => x.asin(),
            Function::Acos => x.acos(),
            Function::Atan => x.atan(),
            Function::Sinh => x.sinh(),
            Function::Cosh => x.cosh(),
            Function::Tanh => x.tanh(),
            Function::Exp => x.exp(),
            Function::Ln => x.ln(),
            Function::Sqrt => x.sqrt(),
            Function::Abs => {
                if x.re() < 0.0 {
                    -x
                } else {
                    x
                }
            }
        }
    }
}

/// A named value an expression reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Symbol {
    /// Coordinate qᵢ.
    Coordinate(usize),
    /// Velocity q̇ᵢ.
    Velocity(usize),
    /// Time t.
    Time,
    /// Parameter i (its current value is read at every evaluation).
    Parameter(usize),
}

/// The names an expression may use, in the order of their indices.
#[derive(Debug, Clone, Copy)]
pub struct Names<'a> {
    /// Coordinate names.
    pub coordinates: &'a [&'static str],
    /// Velocity names (`v` + coordinate name).
    pub velocities: &'a [&'static str],
    /// Parameter names.
    pub parameters: &'a [&'static str],
    /// Whether `t` and the velocities may be used (a symmetry generator ξ(q) depends on q
    /// and the parameters only).
    pub phase_space: bool,
}

impl Names<'_> {
    /// The symbol named `name`, if any.
    fn symbol(&self, name: &str) -> Option<Symbol> {
        let position = |names: &[&str]| names.iter().position(|known| *known == name);
        if let Some(i) = position(self.coordinates) {
            return Some(Symbol::Coordinate(i));
        }
        if let Some(i) = position(self.parameters) {
            return Some(Symbol::Parameter(i));
        }
        if !self.phase_space {
            return None;
        }
        if let Some(i) = position(self.velocities) {
            return Some(Symbol::Velocity(i));
        }
        (name == "t").then_some(Symbol::Time)
    }

    /// The known symbols, as listed in an error message.
    fn known(&self) -> String {
        let mut names: Vec<&str> = self.coordinates.to_vec();
        if self.phase_space {
            names.extend(self.velocities);
            names.push("t");
        }
        names.extend(self.parameters);
        names.join(", ")
    }
}

/// A binary operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Binary {
    Add,
    Subtract,
    Multiply,
    Divide,
    /// xʸ with y depending on the variables: exp(y ln x).
    Power,
    /// xʸ with y free of t, q and q̇ (a parameter, or a non-integer number).
    PowerConstant,
    /// atan2(y, x).
    Atan2,
}

impl Binary {
    /// x ∘ y in any scalar type.
    #[inline]
    fn apply<D: Scalar>(self, x: D, y: D) -> D {
        match self {
            Binary::Add => x + y,
            Binary::Subtract => x - y,
            Binary::Multiply => x * y,
            Binary::Divide => x / y,
            Binary::Power => x.powd(y),
            Binary::PowerConstant => x.powf(y.re()),
            Binary::Atan2 => x.atan2(y),
        }
    }
}

/// One node of the parse tree, its children by index in the arena.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Node {
    Number(f64),
    Symbol(Symbol),
    Negate(usize),
    /// xⁿ, n an integer literal.
    PowerInteger(usize, i32),
    Call(Function, usize),
    Binary(Binary, usize, usize),
}

/// One instruction of the postfix tape. The top of the stack is kept apart, in a local
/// (the accumulator): a load pushes the accumulator and replaces it, a unary operation
/// changes it in place, a binary one combines it with the value it pops.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    /// Load a number.
    Number(f64),
    /// Load a symbol's value.
    Load(Symbol),
    /// Load the square of a symbol's value.
    LoadSquare(Symbol),
    /// x ↦ −x.
    Negate,
    /// x ↦ c·x.
    Scale(f64),
    /// x ↦ x + c.
    Shift(f64),
    /// x ↦ x / c.
    DivideBy(f64),
    /// x ↦ 1/x.
    Reciprocal,
    /// x ↦ x·x.
    Square,
    /// x ↦ xⁿ.
    PowerInteger(i32),
    /// x ↦ f(x).
    Call(Function),
    /// Pop y: x ↦ y ∘ x.
    Binary(Binary),
    /// x ↦ x ∘ s, s a symbol's value.
    WithSymbol(Binary, Symbol),
    /// x ↦ x ∘ s², s a symbol's value.
    WithSquare(Binary, Symbol),
}

/// How L depends on q̇, as far as the expression's structure shows: a sum of a part free of
/// q̇ (`free`), a part linear in q̇ and a quadratic form in q̇, the last two with constant
/// coefficients; anything else is `None` (general).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VelocityForm {
    /// The part free of q̇: absent, constant (numbers and parameters), or depending on t, q.
    free: Free,
    /// Whether terms linear in q̇ (constant coefficients) appear.
    linear: bool,
    /// Whether terms quadratic in q̇ (constant coefficients) appear.
    quadratic: bool,
}

/// The part of an expression free of q̇.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
enum Free {
    Absent,
    Constant,
    Varying,
}

impl VelocityForm {
    /// Free of q̇, constant or not.
    fn free(varying: bool) -> VelocityForm {
        VelocityForm {
            free: if varying {
                Free::Varying
            } else {
                Free::Constant
            },
            linear: false,
            quadratic: false,
        }
    }

    /// Whether q̇ appears at all.
    fn has_velocity(self) -> bool {
        self.linear || self.quadratic
    }

    /// Whether the expression is ½q̇ᵀMq̇ − V(t, q) with M constant: quadratic terms in q̇
    /// with constant coefficients, no linear ones.
    pub fn is_constant_mass(self) -> bool {
        self.quadratic && !self.linear
    }

    /// The form of a sum or difference.
    fn sum(a: VelocityForm, b: VelocityForm) -> VelocityForm {
        VelocityForm {
            free: a.free.max(b.free),
            linear: a.linear || b.linear,
            quadratic: a.quadratic || b.quadratic,
        }
    }

    /// The form of a product, `None` if a term of degree above 2 or a varying coefficient
    /// of q̇ may appear.
    fn product(a: VelocityForm, b: VelocityForm) -> Option<VelocityForm> {
        let degrees = |form: VelocityForm| [form.free != Free::Absent, form.linear, form.quadratic];
        let (da, db) = (degrees(a), degrees(b));
        let mut result = VelocityForm {
            free: Free::Absent,
            linear: false,
            quadratic: false,
        };
        for (i, &x) in da.iter().enumerate() {
            for (j, &y) in db.iter().enumerate() {
                if !(x && y) {
                    continue;
                }
                let varying =
                    (i == 0 && a.free == Free::Varying) || (j == 0 && b.free == Free::Varying);
                match i + j {
                    0 => {
                        result.free = if varying {
                            Free::Varying
                        } else {
                            Free::Constant
                        }
                    }
                    _ if varying => return None,
                    1 => result.linear = true,
                    2 => result.quadratic = true,
                    _ => return None,
                }
            }
        }
        Some(result)
    }
}

/// What the structure of an expression shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Properties {
    /// Whether t appears.
    pub time: bool,
    /// How q̇ appears (`None`: in a way the analysis does not follow).
    pub velocity: Option<VelocityForm>,
}

/// A parsed expression: its parse tree and its properties. [`Expression::compile`] turns it
/// into a [`Tape`] for given parameter values.
#[derive(Debug, Clone, PartialEq)]
pub struct Expression {
    nodes: Vec<Node>,
    root: usize,
    properties: Properties,
}

/// What [`Expression::compile`] does with the velocities.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Velocities {
    /// Read them.
    Read,
    /// Set them to zero (the part of L free of q̇, for a constant-mass L).
    Zero,
}

impl Expression {
    /// Parse `text`, the field `field` of a text model (named in errors), with the symbols
    /// of `names`.
    pub fn parse(text: &str, field: &str, names: &Names<'_>) -> Result<Expression, TextError> {
        let mut parser = Parser {
            text,
            field,
            names,
            position: 0,
            nodes: Vec::new(),
            nesting: 0,
        };
        parser.skip_space();
        if parser.position == text.len() {
            return Err(TextError::Empty {
                field: field.into(),
            });
        }
        let root = parser.sum()?;
        parser.skip_space();
        if parser.position < text.len() {
            let found = parser.peek_char().unwrap_or(' ');
            return Err(parser.syntax(
                parser.position,
                if found == ')' {
                    "unbalanced ')': no '(' to close".into()
                } else {
                    format!("unexpected '{found}' after a complete expression")
                },
            ));
        }
        let expression = Expression {
            properties: properties(&parser.nodes, root),
            nodes: parser.nodes,
            root,
        };
        // The deepest tape for any parameter values: NaN is neither 0 nor 1, so no
        // instruction folds away for it (x + 0 is x, 1/x a reciprocal; for other values the
        // tape is as deep or less).
        let parameters = vec![f64::NAN; names.parameters.len()];
        if expression.compile(&parameters, Velocities::Read).depth > MAX_STACK {
            return Err(TextError::TooDeep {
                field: field.into(),
                limit: MAX_STACK,
            });
        }
        Ok(expression)
    }

    /// What the expression's structure shows (t, how q̇ appears).
    pub fn properties(&self) -> Properties {
        self.properties
    }

    /// The tape of the expression with the parameter values `parameters` folded in.
    pub fn compile(&self, parameters: &[f64], velocities: Velocities) -> Tape {
        let folding = Folding {
            nodes: &self.nodes,
            parameters,
            velocities,
        };
        let mut ops = Vec::new();
        folding.emit(self.root, &mut ops);
        let depth = stack_depth(&ops);
        Tape { ops, depth }
    }

    /// The constant coefficients of a quadratic form in q̇: the matrix Q of the terms
    /// q̇ᵀQq̇ of the expression with `parameters`, if it is ½q̇ᵀMq̇ + (terms free of q̇)
    /// with M = Q + Qᵀ; `None` if it is not (a term linear in q̇, a coefficient that is not
    /// constant).
    pub fn quadratic_form(&self, parameters: &[f64], n: usize) -> Option<Vec<f64>> {
        let polynomial = Polynomial::of(&self.nodes, self.root, parameters, n)?;
        polynomial
            .linear
            .iter()
            .all(|c| *c == 0.0)
            .then_some(polynomial.quadratic)
    }
}

/// An expression compiled for given parameter values: a postfix program of [`Op`]s.
#[derive(Debug, Clone, PartialEq)]
pub struct Tape {
    ops: Vec<Op>,
    depth: usize,
}

impl Tape {
    /// The value at (t, q, q̇).
    #[inline]
    pub fn evaluate<D: Scalar>(&self, t: D, q: &[D], v: &[D]) -> D {
        // The smallest stack that holds the tape: it is zeroed at every evaluation.
        if self.depth <= 1 {
            self.run::<D, 1>(t, q, v)
        } else if self.depth <= 8 {
            self.run::<D, 8>(t, q, v)
        } else {
            self.run::<D, MAX_STACK>(t, q, v)
        }
    }

    /// [`Expression::evaluate`] on a stack of `S` ≥ the tape's depth slots.
    #[inline]
    fn run<D: Scalar, const S: usize>(&self, t: D, q: &[D], v: &[D]) -> D {
        // Parameters are folded into the tape as numbers: no load reads one.
        let fetch = |symbol: Symbol| match symbol {
            Symbol::Coordinate(i) => q[i],
            Symbol::Velocity(i) => v[i],
            Symbol::Time => t,
            Symbol::Parameter(_) => unreachable!("parameters are folded into numbers"),
        };
        // The accumulator holds the top of the stack; `stack[..top]` the values below it (the
        // first load pushes the accumulator's initial zero, never read).
        let mut accumulator = D::from(0.0);
        let mut stack = [D::from(0.0); S];
        let mut top = 0;
        for op in &self.ops {
            let x = accumulator;
            accumulator = match *op {
                Op::Number(_) | Op::Load(_) | Op::LoadSquare(_) => {
                    stack[top] = x;
                    top += 1;
                    match *op {
                        Op::Number(value) => D::from(value),
                        Op::Load(symbol) => fetch(symbol),
                        Op::LoadSquare(symbol) => {
                            let value = fetch(symbol);
                            value * value
                        }
                        _ => unreachable!("a load"),
                    }
                }
                Op::Negate => -x,
                Op::Scale(c) => x * c,
                Op::Shift(c) => x + c,
                Op::DivideBy(c) => x / c,
                Op::Reciprocal => x.recip(),
                Op::Square => x * x,
                Op::PowerInteger(n) => x.powi(n),
                // The square root of norms is inlined: as a call it cost a quarter of a
                // Kepler run.
                Op::Call(Function::Sqrt) => x.sqrt(),
                Op::Call(function) => function.apply(x),
                Op::Binary(binary) => {
                    top -= 1;
                    binary.apply(stack[top], x)
                }
                Op::WithSymbol(binary, symbol) => binary.apply(x, fetch(symbol)),
                Op::WithSquare(binary, symbol) => {
                    let value = fetch(symbol);
                    binary.apply(x, value * value)
                }
            };
        }
        accumulator
    }
}

/// The recursive-descent parser over `text`, building the arena `nodes`.
struct Parser<'a> {
    text: &'a str,
    field: &'a str,
    names: &'a Names<'a>,
    /// Byte offset of the next character.
    position: usize,
    nodes: Vec<Node>,
    /// Current nesting of the recursion.
    nesting: usize,
}

impl Parser<'_> {
    /// The 1-based character column of the byte offset `offset`.
    fn column(&self, offset: usize) -> usize {
        self.text[..offset].chars().count() + 1
    }

    /// A syntax error at byte offset `offset`.
    fn syntax(&self, offset: usize, message: String) -> TextError {
        TextError::Syntax {
            field: self.field.into(),
            column: self.column(offset),
            message,
        }
    }

    fn peek_char(&self) -> Option<char> {
        self.text[self.position..].chars().next()
    }

    fn skip_space(&mut self) {
        while let Some(c) = self.peek_char().filter(|c| c.is_whitespace()) {
            self.position += c.len_utf8();
        }
    }

    /// Skip spaces; consume `c` if it comes next.
    fn eat(&mut self, c: char) -> bool {
        self.skip_space();
        if self.peek_char() == Some(c) {
            self.position += c.len_utf8();
            true
        } else {
            false
        }
    }

    /// Add `node` to the arena, or fail beyond [`MAX_NODES`].
    fn push(&mut self, node: Node) -> Result<usize, TextError> {
        if self.nodes.len() == MAX_NODES {
            return Err(TextError::TooLong {
                field: self.field.into(),
                limit: MAX_NODES,
            });
        }
        self.nodes.push(node);
        Ok(self.nodes.len() - 1)
    }

    /// Enter one more level of nesting, or fail beyond [`MAX_NESTING`].
    fn enter(&mut self) -> Result<(), TextError> {
        self.nesting += 1;
        if self.nesting > MAX_NESTING {
            return Err(self.syntax(
                self.position,
                format!("nested more than {MAX_NESTING} levels deep"),
            ));
        }
        Ok(())
    }

    /// sum := product (('+' | '-') product)*
    fn sum(&mut self) -> Result<usize, TextError> {
        let mut left = self.product()?;
        loop {
            let operation = if self.eat('+') {
                Binary::Add
            } else if self.eat('-') {
                Binary::Subtract
            } else {
                return Ok(left);
            };
            let right = self.product()?;
            left = self.push(Node::Binary(operation, left, right))?;
        }
    }

    /// product := unary (('*' | '/') unary)*
    fn product(&mut self) -> Result<usize, TextError> {
        let mut left = self.unary()?;
        loop {
            let operation = if self.eat('*') {
                Binary::Multiply
            } else if self.eat('/') {
                Binary::Divide
            } else {
                return Ok(left);
            };
            let right = self.unary()?;
            left = self.push(Node::Binary(operation, left, right))?;
        }
    }

    /// unary := ('-' | '+') unary | power
    fn unary(&mut self) -> Result<usize, TextError> {
        self.enter()?;
        let node = if self.eat('-') {
            let operand = self.unary()?;
            self.push(Node::Negate(operand))?
        } else if self.eat('+') {
            self.unary()?
        } else {
            self.power()?
        };
        self.nesting -= 1;
        Ok(node)
    }

    /// power := atom ('^' unary)?, right-associative: a^b^c = a^(b^c), -a^2 = -(a^2).
    fn power(&mut self) -> Result<usize, TextError> {
        let base = self.atom()?;
        if !self.eat('^') {
            return Ok(base);
        }
        let exponent = self.unary()?;
        let integer = match self.nodes[exponent] {
            Node::Number(n) => Some(n),
            Node::Negate(inner) => match self.nodes[inner] {
                Node::Number(n) => Some(-n),
                _ => None,
            },
            _ => None,
        }
        .filter(|n| n.fract() == 0.0 && n.abs() <= f64::from(i32::MAX));
        let node = match integer {
            // A whole number below 2³¹ in magnitude converts exactly.
            Some(n) => Node::PowerInteger(base, n as i32),
            None if !depends_on_variables(&self.nodes, exponent) => {
                Node::Binary(Binary::PowerConstant, base, exponent)
            }
            None => Node::Binary(Binary::Power, base, exponent),
        };
        self.push(node)
    }

    /// atom := number | name | name '(' arguments ')' | '(' sum ')'
    fn atom(&mut self) -> Result<usize, TextError> {
        self.skip_space();
        let start = self.position;
        match self.peek_char() {
            None => Err(self.syntax(start, "expected a number, a name or '(' at the end".into())),
            Some('(') => {
                self.position += 1;
                self.enter()?;
                let inner = self.sum()?;
                self.nesting -= 1;
                if self.eat(')') {
                    Ok(inner)
                } else {
                    Err(self.unclosed(start))
                }
            }
            Some(c) if c.is_ascii_digit() || c == '.' => self.number(start),
            Some(c) if c.is_alphabetic() || c == '_' => self.name(start),
            Some(c) => Err(self.syntax(
                start,
                format!("unexpected '{c}': expected a number, a name or '('"),
            )),
        }
    }

    /// The error of a '(' at `start` that is not closed where the parser stands.
    fn unclosed(&self, start: usize) -> TextError {
        let found = match self.peek_char() {
            Some(c) => format!("found '{c}' at column {}", self.column(self.position)),
            None => "found the end".into(),
        };
        self.syntax(
            start,
            format!("unbalanced '(': no ')' to close it ({found})"),
        )
    }

    /// A number: digits, an optional fraction and an optional exponent (`1.5e-3`).
    fn number(&mut self, start: usize) -> Result<usize, TextError> {
        let bytes = self.text.as_bytes();
        let mut end = start;
        let digits = |end: &mut usize| {
            while *end < bytes.len() && bytes[*end].is_ascii_digit() {
                *end += 1;
            }
        };
        digits(&mut end);
        if end < bytes.len() && bytes[end] == b'.' {
            end += 1;
            digits(&mut end);
        }
        if end < bytes.len() && (bytes[end] == b'e' || bytes[end] == b'E') {
            let mut exponent = end + 1;
            if exponent < bytes.len() && (bytes[exponent] == b'+' || bytes[exponent] == b'-') {
                exponent += 1;
            }
            if exponent < bytes.len() && bytes[exponent].is_ascii_digit() {
                end = exponent;
                digits(&mut end);
            }
        }
        let literal = &self.text[start..end];
        let value: f64 = literal
            .parse()
            .map_err(|_| self.syntax(start, format!("malformed number '{literal}'")))?;
        if !value.is_finite() {
            return Err(self.syntax(start, format!("number '{literal}' overflows")));
        }
        self.position = end;
        self.push(Node::Number(value))
    }

    /// A name: a symbol, a constant, or a function applied to its arguments.
    fn name(&mut self, start: usize) -> Result<usize, TextError> {
        let rest = &self.text[start..];
        let length = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        let name = &rest[..length];
        self.position = start + length;
        let call = {
            let save = self.position;
            let open = self.eat('(');
            if !open {
                self.position = save;
            }
            open
        };
        if call {
            return self.call(name, start);
        }
        if let Some(symbol) = self.names.symbol(name) {
            return self.push(Node::Symbol(symbol));
        }
        match name {
            "pi" => return self.push(Node::Number(std::f64::consts::PI)),
            "e" => return self.push(Node::Number(std::f64::consts::E)),
            _ => {}
        }
        if FUNCTION_NAMES.contains(&name) {
            return Err(self.syntax(
                start,
                format!("function '{name}' needs its argument in parentheses: {name}(...)"),
            ));
        }
        Err(TextError::UnknownSymbol {
            field: self.field.into(),
            column: self.column(start),
            symbol: name.into(),
            known: self.names.known(),
        })
    }

    /// The call of `name` (at byte `start`), after its '('.
    fn call(&mut self, name: &str, start: usize) -> Result<usize, TextError> {
        let open = self.position - 1;
        let (function, arity) = match (Function::named(name), name) {
            (Some(function), _) => (Some(function), 1),
            (None, "atan2") => (None, 2),
            _ => {
                return Err(TextError::UnknownFunction {
                    field: self.field.into(),
                    column: self.column(start),
                    name: name.into(),
                    known: FUNCTION_NAMES.join(", "),
                });
            }
        };
        self.enter()?;
        let mut arguments = Vec::with_capacity(arity);
        loop {
            arguments.push(self.sum()?);
            if self.eat(')') {
                break;
            }
            if !self.eat(',') {
                return Err(self.unclosed(open));
            }
        }
        self.nesting -= 1;
        if arguments.len() != arity {
            return Err(self.syntax(
                start,
                format!(
                    "{name} takes {arity} argument{}, found {}",
                    if arity == 1 { "" } else { "s" },
                    arguments.len()
                ),
            ));
        }
        match function {
            Some(function) => self.push(Node::Call(function, arguments[0])),
            None => self.push(Node::Binary(Binary::Atan2, arguments[0], arguments[1])),
        }
    }
}

/// Whether the subtree at `node` reads t, q or q̇.
fn depends_on_variables(nodes: &[Node], node: usize) -> bool {
    match nodes[node] {
        Node::Number(_) | Node::Symbol(Symbol::Parameter(_)) => false,
        Node::Symbol(_) => true,
        Node::Negate(a) | Node::PowerInteger(a, _) | Node::Call(_, a) => {
            depends_on_variables(nodes, a)
        }
        Node::Binary(_, a, b) => depends_on_variables(nodes, a) || depends_on_variables(nodes, b),
    }
}

/// The parse tree with parameter values (and zero velocities, if so asked): what
/// [`Expression::compile`] folds.
struct Folding<'a> {
    nodes: &'a [Node],
    parameters: &'a [f64],
    velocities: Velocities,
}

impl Folding<'_> {
    /// The value of the subtree at `node` if it holds no variable (t, q, and q̇ unless they
    /// are zero): numbers, constants and parameters only.
    fn constant_value(&self, node: usize) -> Option<f64> {
        Some(match self.nodes[node] {
            Node::Number(x) => x,
            Node::Symbol(Symbol::Parameter(i)) => self.parameters[i],
            Node::Symbol(Symbol::Velocity(_)) if self.velocities == Velocities::Zero => 0.0,
            Node::Symbol(_) => return None,
            Node::Negate(a) => -self.constant_value(a)?,
            Node::PowerInteger(a, n) => self.constant_value(a)?.powi(n),
            Node::Call(function, a) => function.apply(self.constant_value(a)?),
            Node::Binary(binary, a, b) => {
                binary.apply(self.constant_value(a)?, self.constant_value(b)?)
            }
        })
    }

    /// The subtree at `node` as an [`Operand`] (a variable or its square), if it is one.
    fn operand(&self, node: usize) -> Option<Operand> {
        let variable = |node: usize| match self.nodes[node] {
            Node::Symbol(symbol) if self.constant_value(node).is_none() => Some(symbol),
            _ => None,
        };
        match self.nodes[node] {
            Node::Symbol(_) => variable(node).map(Operand::Symbol),
            Node::PowerInteger(a, 2) => variable(a).map(Operand::Square),
            _ => None,
        }
    }

    /// Append the postfix code of the subtree at `node` to `ops`: constant subtrees folded,
    /// a product or quotient with a number as one operand scaled, 1/x a reciprocal, x² a
    /// product, a variable (or its square) as the second operand read by the operation.
    fn emit(&self, node: usize, ops: &mut Vec<Op>) {
        if let Some(value) = self.constant_value(node) {
            ops.push(Op::Number(value));
            return;
        }
        let number = |node: usize| self.constant_value(node);
        match self.nodes[node] {
            Node::Number(x) => ops.push(Op::Number(x)),
            Node::Symbol(symbol) => ops.push(Op::Load(symbol)),
            Node::Negate(a) => {
                self.emit(a, ops);
                ops.push(Op::Negate);
            }
            Node::PowerInteger(a, n) => match (n, self.operand(node)) {
                (2, Some(Operand::Square(symbol))) => ops.push(Op::LoadSquare(symbol)),
                _ => {
                    self.emit(a, ops);
                    ops.push(match n {
                        -1 => Op::Reciprocal,
                        2 => Op::Square,
                        _ => Op::PowerInteger(n),
                    });
                }
            },
            Node::Call(function, a) => {
                self.emit(a, ops);
                ops.push(Op::Call(function));
            }
            Node::Binary(binary, a, b) => match (binary, number(a), number(b)) {
                // x + 0 and x − 0 are x.
                (Binary::Add, Some(c), None) | (Binary::Add | Binary::Subtract, None, Some(c))
                    if c == 0.0 =>
                {
                    self.emit(if number(a).is_some() { b } else { a }, ops);
                }
                (Binary::Multiply, Some(c), None) => {
                    self.emit(b, ops);
                    ops.push(Op::Scale(c));
                }
                (Binary::Multiply, None, Some(c)) => {
                    self.emit(a, ops);
                    ops.push(Op::Scale(c));
                }
                (Binary::Divide, Some(1.0), None) => {
                    self.emit(b, ops);
                    ops.push(Op::Reciprocal);
                }
                (Binary::Divide, None, Some(c)) => {
                    self.emit(a, ops);
                    ops.push(Op::DivideBy(c));
                }
                (Binary::Add, Some(c), None) => {
                    self.emit(b, ops);
                    ops.push(Op::Shift(c));
                }
                (Binary::Add, None, Some(c)) => {
                    self.emit(a, ops);
                    ops.push(Op::Shift(c));
                }
                (Binary::Subtract, None, Some(c)) => {
                    self.emit(a, ops);
                    ops.push(Op::Shift(-c));
                }
                _ => self.emit_binary(binary, a, b, ops),
            },
        }
    }

    /// Append the code of a ∘ b, reading a variable operand (b, or a when ∘ commutes) in
    /// the operation itself.
    fn emit_binary(&self, binary: Binary, a: usize, b: usize, ops: &mut Vec<Op>) {
        let fusable = matches!(
            binary,
            Binary::Add | Binary::Subtract | Binary::Multiply | Binary::Divide
        );
        let commutes = matches!(binary, Binary::Add | Binary::Multiply);
        let (first, operand) = match (self.operand(b), self.operand(a)) {
            (Some(operand), _) if fusable => (a, operand),
            (None, Some(operand)) if commutes => (b, operand),
            _ => {
                self.emit(a, ops);
                self.emit(b, ops);
                ops.push(Op::Binary(binary));
                return;
            }
        };
        self.emit(first, ops);
        ops.push(match operand {
            Operand::Symbol(symbol) => Op::WithSymbol(binary, symbol),
            Operand::Square(symbol) => Op::WithSquare(binary, symbol),
        });
    }
}

/// An operand a fused instruction reads itself.
#[derive(Debug, Clone, Copy)]
enum Operand {
    Symbol(Symbol),
    Square(Symbol),
}

/// A polynomial of degree at most 2 in q̇ with constant coefficients, plus a part free of
/// q̇: what [`Expression::quadratic_form`] reads off a constant-mass L.
struct Polynomial {
    /// The part free of q̇: its value if it is constant, `None` if it depends on t or q.
    constant: Option<f64>,
    /// Coefficients of q̇ᵢ.
    linear: Vec<f64>,
    /// Coefficients of q̇ᵢq̇ⱼ, row-major n × n.
    quadratic: Vec<f64>,
    /// The structural degree in q̇ (0, 1 or 2), whatever the coefficients' values.
    degree: u8,
}

impl Polynomial {
    /// Free of q̇: `constant`, or depending on t and q (`None`).
    fn free(constant: Option<f64>, n: usize) -> Polynomial {
        Polynomial {
            constant,
            linear: vec![0.0; n],
            quadratic: vec![0.0; n * n],
            degree: 0,
        }
    }

    /// The polynomial of the subtree at `node`, `None` if it is not one (a varying
    /// coefficient of q̇, a degree above 2, q̇ inside a function).
    fn of(nodes: &[Node], node: usize, parameters: &[f64], n: usize) -> Option<Polynomial> {
        let of = |node| Polynomial::of(nodes, node, parameters, n);
        Some(match nodes[node] {
            Node::Number(x) => Polynomial::free(Some(x), n),
            Node::Symbol(Symbol::Parameter(i)) => Polynomial::free(Some(parameters[i]), n),
            Node::Symbol(Symbol::Velocity(i)) => {
                let mut velocity = Polynomial::free(Some(0.0), n);
                velocity.linear[i] = 1.0;
                velocity.degree = 1;
                velocity
            }
            Node::Symbol(_) => Polynomial::free(None, n),
            Node::Negate(a) => of(a)?.scaled(-1.0),
            Node::PowerInteger(a, power) => {
                let base = of(a)?;
                match power {
                    _ if base.degree == 0 => {
                        Polynomial::free(base.constant.map(|c| c.powi(power)), n)
                    }
                    1 => base,
                    2 => base.times(&base)?,
                    _ => return None,
                }
            }
            Node::Call(function, a) => {
                let argument = of(a)?;
                if argument.degree > 0 {
                    return None;
                }
                Polynomial::free(argument.constant.map(|c| function.apply(c)), n)
            }
            Node::Binary(binary, a, b) => {
                let (x, y) = (of(a)?, of(b)?);
                match binary {
                    Binary::Add => x.plus(&y, 1.0),
                    Binary::Subtract => x.plus(&y, -1.0),
                    Binary::Multiply => x.times(&y)?,
                    Binary::Divide if y.degree == 0 => match y.constant {
                        Some(c) => x.scaled(c.recip()),
                        None if x.degree == 0 => Polynomial::free(None, n),
                        None => return None,
                    },
                    _ if x.degree > 0 || y.degree > 0 => return None,
                    _ => Polynomial::free(
                        x.constant.zip(y.constant).map(|(x, y)| binary.apply(x, y)),
                        n,
                    ),
                }
            }
        })
    }

    /// c · self.
    fn scaled(mut self, c: f64) -> Polynomial {
        self.constant = self.constant.map(|x| x * c);
        self.linear.iter_mut().for_each(|x| *x *= c);
        self.quadratic.iter_mut().for_each(|x| *x *= c);
        self
    }

    /// self + sign · other.
    fn plus(mut self, other: &Polynomial, sign: f64) -> Polynomial {
        self.constant = self.constant.zip(other.constant).map(|(x, y)| x + sign * y);
        for (x, y) in self.linear.iter_mut().zip(&other.linear) {
            *x += sign * y;
        }
        for (x, y) in self.quadratic.iter_mut().zip(&other.quadratic) {
            *x += sign * y;
        }
        self.degree = self.degree.max(other.degree);
        self
    }

    /// self · other, `None` above degree 2 or for a varying factor of a term in q̇.
    fn times(&self, other: &Polynomial) -> Option<Polynomial> {
        let degree = self.degree + other.degree;
        if degree > 2
            || (self.degree > 0 && other.constant.is_none())
            || (other.degree > 0 && self.constant.is_none())
        {
            return None;
        }
        let n = self.linear.len();
        let (a, b) = (self.constant.unwrap_or(0.0), other.constant.unwrap_or(0.0));
        let mut product =
            Polynomial::free(self.constant.zip(other.constant).map(|(x, y)| x * y), n);
        product.degree = degree;
        for i in 0..n {
            product.linear[i] = a * other.linear[i] + b * self.linear[i];
            for j in 0..n {
                product.quadratic[i * n + j] = a * other.quadratic[i * n + j]
                    + b * self.quadratic[i * n + j]
                    + self.linear[i] * other.linear[j];
            }
        }
        Some(product)
    }
}

/// The most values `tape` keeps on the stack at once.
fn stack_depth(tape: &[Op]) -> usize {
    let mut depth = 0usize;
    let mut deepest = 0;
    for op in tape {
        match op {
            Op::Number(_) | Op::Load(_) | Op::LoadSquare(_) => depth += 1,
            Op::Binary(_) => depth -= 1,
            _ => {}
        }
        deepest = deepest.max(depth);
    }
    deepest
}

/// What the structure of the subtree at `root` shows.
fn properties(nodes: &[Node], root: usize) -> Properties {
    Properties {
        time: nodes.contains(&Node::Symbol(Symbol::Time)),
        velocity: velocity_form(nodes, root),
    }
}

/// How the subtree at `node` depends on q̇ (see [`VelocityForm`]).
fn velocity_form(nodes: &[Node], node: usize) -> Option<VelocityForm> {
    let form = |node| velocity_form(nodes, node);
    match nodes[node] {
        Node::Number(_) | Node::Symbol(Symbol::Parameter(_)) => Some(VelocityForm::free(false)),
        Node::Symbol(Symbol::Velocity(_)) => Some(VelocityForm {
            free: Free::Absent,
            linear: true,
            quadratic: false,
        }),
        Node::Symbol(_) => Some(VelocityForm::free(true)),
        Node::Negate(a) => form(a),
        Node::PowerInteger(a, n) => {
            let base = form(a)?;
            match n {
                0 => Some(VelocityForm::free(false)),
                1 => Some(base),
                2 => VelocityForm::product(base, base),
                _ if base.has_velocity() => None,
                _ => Some(base),
            }
        }
        Node::Call(_, a) => {
            let argument = form(a)?;
            (!argument.has_velocity()).then_some(VelocityForm::free(argument.free == Free::Varying))
        }
        Node::Binary(binary, a, b) => {
            let (x, y) = (form(a)?, form(b)?);
            match binary {
                Binary::Add | Binary::Subtract => Some(VelocityForm::sum(x, y)),
                Binary::Multiply => VelocityForm::product(x, y),
                Binary::Divide if !y.has_velocity() => {
                    // x / y = x · (1/y), 1/y free of q̇ and as varying as y.
                    VelocityForm::product(x, VelocityForm::free(y.free == Free::Varying))
                }
                _ if x.has_velocity() || y.has_velocity() => None,
                _ => Some(VelocityForm::free(
                    x.free == Free::Varying || y.free == Free::Varying,
                )),
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const COORDINATES: [&str; 2] = ["x", "y"];
    const VELOCITIES: [&str; 2] = ["vx", "vy"];
    const PARAMETERS: [&str; 1] = ["mu"];

    fn names() -> Names<'static> {
        Names {
            coordinates: &COORDINATES,
            velocities: &VELOCITIES,
            parameters: &PARAMETERS,
            phase_space: true,
        }
    }

    fn parse(text: &str) -> Result<Expression, TextError> {
        Expression::parse(text, "lagrangian", &names())
    }

    /// The value at t = 0.5, q = (1.5, −2), q̇ = (0.25, 3), μ = 2.
    fn value(text: &str) -> f64 {
        let expression = parse(text).unwrap_or_else(|error| panic!("{text}: {error}"));
        expression
            .compile(&[2.0], Velocities::Read)
            .evaluate(0.5, &[1.5, -2.0], &[0.25, 3.0])
    }

    /// |a − b| ≤ 1e-15 max(1, |b|).
    fn close(a: f64, b: f64) {
        assert!((a - b).abs() <= 1e-15 * b.abs().max(1.0), "{a} against {b}");
    }

    #[test]
    fn precedence_and_associativity() {
        assert_eq!(value("1 + 2 * 3"), 7.0);
        assert_eq!(value("(1 + 2) * 3"), 9.0);
        assert_eq!(value("8 / 4 / 2"), 1.0);
        assert_eq!(value("8 - 4 - 2"), 2.0);
        // ^ is right-associative and binds tighter than unary minus and * /.
        assert_eq!(value("2^3^2"), 512.0);
        assert_eq!(value("-2^2"), -4.0);
        assert_eq!(value("(-2)^2"), 4.0);
        assert_eq!(value("2^-1"), 0.5);
        assert_eq!(value("2 * 3^2"), 18.0);
        assert_eq!(value("x^2"), 2.25);
        assert_eq!(value("-x"), -1.5);
        assert_eq!(value("--x"), 1.5);
        assert_eq!(value("+x - -y"), -0.5);
        assert_eq!(value("x*-y"), 3.0);
        assert_eq!(value("y^3"), -8.0);
        assert_eq!(value("x^-1"), 1.0 / 1.5);
        close(value("mu^x"), 2f64.powf(1.5));
        assert_eq!(value("x^mu"), 2.25);
        assert_eq!(value("x^0.5"), 1.5f64.sqrt());
        close(value("mu^(x)"), 2f64.powf(1.5));
    }

    #[test]
    fn numbers_constants_symbols_and_functions() {
        assert_eq!(value("1.5e-3"), 1.5e-3);
        assert_eq!(value("2E2 + .5 + 3."), 203.5);
        assert_eq!(value("pi"), std::f64::consts::PI);
        assert_eq!(value("e"), std::f64::consts::E);
        assert_eq!(value("t + mu + vx + vy"), 5.75);
        assert_eq!(value("sin(x)"), 1.5f64.sin());
        assert_eq!(value("cos(x) + tan(x)"), 1.5f64.cos() + 1.5f64.tan());
        close(value("exp(vx) * ln(x) / log(x)"), 0.25f64.exp());
        assert_eq!(value("sqrt(abs(y))"), 2f64.sqrt());
        assert_eq!(value("sinh(vx) + cosh(vx) - tanh(vx)"), {
            0.25f64.sinh() + 0.25f64.cosh() - 0.25f64.tanh()
        });
        assert_eq!(value("asin(vx) + acos(vx) + atan(y)"), {
            0.25f64.asin() + 0.25f64.acos() + (-2f64).atan()
        });
        assert_eq!(value("atan2(y, x)"), (-2f64).atan2(1.5));
        assert_eq!(value(" 1/sqrt( x^2 + y^2 ) "), 1.0 / 6.25f64.sqrt());
    }

    #[test]
    fn evaluation_is_generic_over_duals() {
        use num_dual::{Dual64, DualStruct};
        let expression = parse("x^3 * sin(x) + 1/x").unwrap();
        let x = Dual64::from(1.5).derivative();
        let y = Dual64::from(-2.0);
        let tape = expression.compile(&[2.0], Velocities::Read);
        let value = tape.evaluate(Dual64::from(0.0), &[x, y], &[y, y]);
        let expected = 3.0 * 2.25 * 1.5f64.sin() + 1.5f64.powi(3) * 1.5f64.cos() - 1.0 / 2.25;
        assert!((value.eps - expected).abs() < 1e-14, "{}", value.eps);
        close(value.re(), 1.5f64.powi(3) * 1.5f64.sin() + 1.0 / 1.5);
    }

    #[test]
    fn errors_name_the_column_and_the_symbol() {
        let error = parse("0.5*(vx^2 + vy^2) + z").unwrap_err();
        assert_eq!(
            error.to_string(),
            "unknown symbol 'z' at column 21 of lagrangian (known: x, y, vx, vy, t, mu)"
        );
        let columns = [
            ("", None),
            ("   ", None),
            ("(x + y", Some(1)),
            ("x + y)", Some(6)),
            ("x + * y", Some(5)),
            ("x +", Some(4)),
            ("sin x", Some(1)),
            ("sinus(x)", Some(1)),
            ("atan2(x)", Some(1)),
            ("sin(x, y)", Some(1)),
            ("x # y", Some(3)),
            ("2 x", Some(3)),
            ("1e999", Some(1)),
            ("sin(x", Some(4)),
            ("ξ + x", Some(1)),
            ("x + ξ", Some(5)),
        ];
        for (text, column) in columns {
            let error = parse(text).unwrap_err();
            let found = match &error {
                TextError::Empty { .. } => None,
                TextError::Syntax { column, .. }
                | TextError::UnknownSymbol { column, .. }
                | TextError::UnknownFunction { column, .. } => Some(*column),
                other => panic!("{text}: {other}"),
            };
            assert_eq!(found, column, "{text}: {error}");
            if let Some(column) = column {
                assert!(
                    error.to_string().contains(&format!("column {column}")),
                    "{error}"
                );
            }
        }
        assert!(matches!(
            parse("sinus(x)"),
            Err(TextError::UnknownFunction { name, .. }) if name == "sinus"
        ));
    }

    #[test]
    fn hostile_nesting_and_depth_are_errors() {
        let nested = format!("{}x{}", "(".repeat(10_000), ")".repeat(10_000));
        assert!(matches!(parse(&nested), Err(TextError::Syntax { .. })));
        let minus = format!("{}x", "-".repeat(10_000));
        assert!(matches!(parse(&minus), Err(TextError::Syntax { .. })));
        let right = format!("{}x{}", "(x+y)*(".repeat(70), ")".repeat(70));
        assert!(matches!(parse(&right), Err(TextError::TooDeep { .. })));
        // The longest expression, folded and analysed on a test thread's stack.
        let long = vec!["x"; MAX_NODES / 2].join(" + ");
        assert_eq!(value(&long), 1.5 * (MAX_NODES / 2) as f64);
        let form = parse(&long).unwrap().quadratic_form(&[2.0], 2);
        assert_eq!(form, Some(vec![0.0; 4]));
        let longer = vec!["x"; MAX_NODES / 2 + 1].join(" + ");
        assert!(matches!(parse(&longer), Err(TextError::TooLong { .. })));
    }

    #[test]
    fn time_and_the_form_in_velocity_are_read_off_the_structure() {
        let properties = |text: &str| parse(text).unwrap().properties();
        assert!(properties("t*x").time);
        assert!(!properties("x").time);
        let constant_mass = |text: &str| {
            properties(text)
                .velocity
                .is_some_and(VelocityForm::is_constant_mass)
        };
        for text in [
            "0.5*(vx^2 + vy^2) + 1/sqrt(x^2 + y^2)",
            "vx*vy*mu - cos(x)*t",
            "(vx + 2*vy)^2/mu - x^4",
            "-(vx^2)/2 + x",
            "(vx - vy)*(vx + vy)",
            "vx^2/(2*mu)",
        ] {
            assert!(constant_mass(text), "{text}");
        }
        for text in [
            "vx^2*x",
            "vx^2 + vx",
            "(vx + x)^2",
            "vx^3",
            "sqrt(vx^2 + 1)",
            "vx^2/x",
            "vx*vy*vx",
            "x + y",
            "vx^2*t",
            "vx^mu",
        ] {
            assert!(!constant_mass(text), "{text}");
        }
    }

    #[test]
    fn constants_fold_and_numbers_scale() {
        let tape = |text: &str, velocities| parse(text).unwrap().compile(&[2.0], velocities);
        let expression = tape("2*pi*x + 1/y - x/4", Velocities::Read);
        assert_eq!(
            expression.ops,
            [
                Op::Load(Symbol::Coordinate(0)),
                Op::Scale(2.0 * std::f64::consts::PI),
                Op::Load(Symbol::Coordinate(1)),
                Op::Reciprocal,
                Op::Binary(Binary::Add),
                Op::Load(Symbol::Coordinate(0)),
                Op::DivideBy(4.0),
                Op::Binary(Binary::Subtract),
            ]
        );
        assert_eq!(expression.depth, 2);
        let kepler = "0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)";
        let potential = [
            Op::Number(2.0),
            Op::LoadSquare(Symbol::Coordinate(0)),
            Op::WithSquare(Binary::Add, Symbol::Coordinate(1)),
            Op::Call(Function::Sqrt),
            Op::Binary(Binary::Divide),
        ];
        let mut full = vec![
            Op::LoadSquare(Symbol::Velocity(0)),
            Op::WithSquare(Binary::Add, Symbol::Velocity(1)),
            Op::Scale(0.5),
        ];
        full.extend(potential);
        full.push(Op::Binary(Binary::Add));
        assert_eq!(tape(kepler, Velocities::Read).ops, full);
        assert_eq!(tape(kepler, Velocities::Read).depth, 3);
        // The part free of q̇: the kinetic terms fold to 0, and + 0 goes.
        assert_eq!(tape(kepler, Velocities::Zero).ops, potential);
        // Parameters are folded: μ = 1 makes 1/sqrt(...) a reciprocal.
        let unit = parse(kepler).unwrap().compile(&[1.0], Velocities::Zero);
        assert_eq!(unit.ops[2..], [Op::Call(Function::Sqrt), Op::Reciprocal]);
    }

    #[test]
    fn quadratic_forms_are_read_off_constant_mass_expressions() {
        let form = |text: &str| parse(text).unwrap().quadratic_form(&[2.0], 2);
        assert_eq!(
            form("0.5*(vx^2 + vy^2) + mu/sqrt(x^2 + y^2)"),
            Some(vec![0.5, 0.0, 0.0, 0.5])
        );
        // (vx + 2vy)²/μ: Q + Qᵀ = [[1, 2], [2, 4]], the Hessian of (vx + 2vy)²/2.
        assert_eq!(
            form("(vx + 2*vy)^2/mu - x^4*cos(t)"),
            Some(vec![0.5, 1.0, 1.0, 2.0])
        );
        assert_eq!(form("-(vx*vy)/2 + x"), Some(vec![0.0, -0.5, 0.0, 0.0]));
        for text in [
            "vx^2 + vx",
            "vx^2*x",
            "sqrt(vx^2)",
            "vx^3",
            "vx^2/x",
            "vx^mu",
        ] {
            assert!(form(text).is_none(), "{text}");
        }
    }
}
