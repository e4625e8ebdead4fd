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

/// One instruction of the postfix tape.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Op {
    /// Push a number.
    Number(f64),
    /// Push a symbol's value.
    Symbol(Symbol),
    /// Pop x, push −x.
    Negate,
    /// Pop x, push c·x.
    Scale(f64),
    /// Pop x, push x + c.
    Shift(f64),
    /// Pop x, push x / c.
    DivideBy(f64),
    /// Pop x, push 1/x.
    Reciprocal,
    /// Pop x, push x² (as x·x).
    Square,
    /// Pop x, push xⁿ.
    PowerInteger(i32),
    /// Pop x, push f(x).
    Call(Function),
    /// Pop y then x, push x ∘ y.
    Binary(Binary),
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

/// A parsed expression: its tape and its properties.
#[derive(Debug, Clone, PartialEq)]
pub struct Expression {
    tape: Vec<Op>,
    depth: usize,
    properties: Properties,
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
        let mut tape = Vec::new();
        emit(&parser.nodes, root, &mut tape);
        let depth = stack_depth(&tape);
        if depth > MAX_STACK {
            return Err(TextError::TooDeep {
                field: field.into(),
                limit: MAX_STACK,
            });
        }
        Ok(Expression {
            tape,
            depth,
            properties: properties(&parser.nodes, root),
        })
    }

    /// What the expression's structure shows (t, how q̇ appears).
    pub fn properties(&self) -> Properties {
        self.properties
    }

    /// The value at (t, q, q̇) with the parameter values `parameters`.
    #[inline]
    pub fn evaluate<D: Scalar>(&self, parameters: &[f64], t: D, q: &[D], v: &[D]) -> D {
        if self.depth <= 8 {
            self.run::<D, 8>(parameters, t, q, v)
        } else {
            self.run::<D, MAX_STACK>(parameters, t, q, v)
        }
    }

    /// [`Expression::evaluate`] on a stack of `S` ≥ the tape's depth slots.
    #[inline]
    fn run<D: Scalar, const S: usize>(&self, parameters: &[f64], t: D, q: &[D], v: &[D]) -> D {
        let mut stack = [D::from(0.0); S];
        let mut top = 0;
        for op in &self.tape {
            match *op {
                Op::Number(x) => {
                    stack[top] = D::from(x);
                    top += 1;
                }
                Op::Symbol(symbol) => {
                    stack[top] = match symbol {
                        Symbol::Coordinate(i) => q[i],
                        Symbol::Velocity(i) => v[i],
                        Symbol::Time => t,
                        Symbol::Parameter(i) => D::from(parameters[i]),
                    };
                    top += 1;
                }
                Op::Negate => stack[top - 1] = -stack[top - 1],
                Op::Scale(c) => stack[top - 1] *= c,
                Op::Shift(c) => stack[top - 1] += c,
                Op::DivideBy(c) => stack[top - 1] /= c,
                Op::Reciprocal => stack[top - 1] = stack[top - 1].recip(),
                Op::Square => stack[top - 1] = stack[top - 1] * stack[top - 1],
                Op::PowerInteger(n) => stack[top - 1] = stack[top - 1].powi(n),
                Op::Call(function) => stack[top - 1] = function.apply(stack[top - 1]),
                Op::Binary(binary) => {
                    top -= 1;
                    let (x, y) = (stack[top - 1], stack[top]);
                    stack[top - 1] = match binary {
                        Binary::Add => x + y,
                        Binary::Subtract => x - y,
                        Binary::Multiply => x * y,
                        Binary::Divide => x / y,
                        Binary::Power => x.powd(y),
                        Binary::PowerConstant => x.powf(y.re()),
                        Binary::Atan2 => x.atan2(y),
                    };
                }
            }
        }
        stack[0]
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

    fn push(&mut self, node: Node) -> usize {
        self.nodes.push(node);
        self.nodes.len() - 1
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
            left = self.push(Node::Binary(operation, left, right));
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
            left = self.push(Node::Binary(operation, left, right));
        }
    }

    /// unary := ('-' | '+') unary | power
    fn unary(&mut self) -> Result<usize, TextError> {
        self.enter()?;
        let node = if self.eat('-') {
            let operand = self.unary()?;
            self.push(Node::Negate(operand))
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
        Ok(self.push(node))
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
        Ok(self.push(Node::Number(value)))
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
            return Ok(self.push(Node::Symbol(symbol)));
        }
        match name {
            "pi" => return Ok(self.push(Node::Number(std::f64::consts::PI))),
            "e" => return Ok(self.push(Node::Number(std::f64::consts::E))),
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
        Ok(match function {
            Some(function) => self.push(Node::Call(function, arguments[0])),
            None => self.push(Node::Binary(Binary::Atan2, arguments[0], arguments[1])),
        })
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

/// The value of the subtree at `node` if it holds numbers only (no symbol).
fn constant_value(nodes: &[Node], node: usize) -> Option<f64> {
    Some(match nodes[node] {
        Node::Number(x) => x,
        Node::Symbol(_) => return None,
        Node::Negate(a) => -constant_value(nodes, a)?,
        Node::PowerInteger(a, n) => constant_value(nodes, a)?.powi(n),
        Node::Call(function, a) => function.apply(constant_value(nodes, a)?),
        Node::Binary(binary, a, b) => {
            let (x, y) = (constant_value(nodes, a)?, constant_value(nodes, b)?);
            match binary {
                Binary::Add => x + y,
                Binary::Subtract => x - y,
                Binary::Multiply => x * y,
                Binary::Divide => x / y,
                Binary::Power | Binary::PowerConstant => x.powf(y),
                Binary::Atan2 => x.atan2(y),
            }
        }
    })
}

/// Append the postfix code of the subtree at `node` to `tape`: constant subtrees folded, a
/// product or quotient with a number as one operand scaled, 1/x a reciprocal, x² a product.
fn emit(nodes: &[Node], node: usize, tape: &mut Vec<Op>) {
    if let Some(value) = constant_value(nodes, node) {
        tape.push(Op::Number(value));
        return;
    }
    let number = |node: usize| constant_value(nodes, node);
    match nodes[node] {
        Node::Number(x) => tape.push(Op::Number(x)),
        Node::Symbol(symbol) => tape.push(Op::Symbol(symbol)),
        Node::Negate(a) => {
            emit(nodes, a, tape);
            tape.push(Op::Negate);
        }
        Node::PowerInteger(a, n) => {
            emit(nodes, a, tape);
            tape.push(match n {
                -1 => Op::Reciprocal,
                2 => Op::Square,
                _ => Op::PowerInteger(n),
            });
        }
        Node::Call(function, a) => {
            emit(nodes, a, tape);
            tape.push(Op::Call(function));
        }
        Node::Binary(binary, a, b) => match (binary, number(a), number(b)) {
            (Binary::Multiply, Some(c), None) => {
                emit(nodes, b, tape);
                tape.push(Op::Scale(c));
            }
            (Binary::Multiply, None, Some(c)) => {
                emit(nodes, a, tape);
                tape.push(Op::Scale(c));
            }
            (Binary::Divide, Some(c), None) if c == 1.0 => {
                emit(nodes, b, tape);
                tape.push(Op::Reciprocal);
            }
            (Binary::Divide, None, Some(c)) => {
                emit(nodes, a, tape);
                tape.push(Op::DivideBy(c));
            }
            (Binary::Add, Some(c), None) => {
                emit(nodes, b, tape);
                tape.push(Op::Shift(c));
            }
            (Binary::Add, None, Some(c)) => {
                emit(nodes, a, tape);
                tape.push(Op::Shift(c));
            }
            (Binary::Subtract, None, Some(c)) => {
                emit(nodes, a, tape);
                tape.push(Op::Shift(-c));
            }
            _ => {
                emit(nodes, a, tape);
                emit(nodes, b, tape);
                tape.push(Op::Binary(binary));
            }
        },
    }
}

/// The most values `tape` keeps on the stack at once.
fn stack_depth(tape: &[Op]) -> usize {
    let mut depth = 0usize;
    let mut deepest = 0;
    for op in tape {
        match op {
            Op::Number(_) | Op::Symbol(_) => depth += 1,
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
        time: nodes.iter().any(|node| *node == Node::Symbol(Symbol::Time)),
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
        expression.evaluate(&[2.0], 0.5, &[1.5, -2.0], &[0.25, 3.0])
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
        let value = expression.evaluate(&[2.0], Dual64::from(0.0), &[x, y], &[y, y]);
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
        let right = format!("{}x{}", "x*(".repeat(70), ")".repeat(70));
        assert!(matches!(parse(&right), Err(TextError::TooDeep { .. })));
        let long = vec!["x"; 10_000].join(" + ");
        assert_eq!(value(&long), 15_000.0);
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
        let expression = parse("2*pi*x + 1/y - x/4").unwrap();
        assert_eq!(
            expression.tape,
            [
                Op::Symbol(Symbol::Coordinate(0)),
                Op::Scale(2.0 * std::f64::consts::PI),
                Op::Symbol(Symbol::Coordinate(1)),
                Op::Reciprocal,
                Op::Binary(Binary::Add),
                Op::Symbol(Symbol::Coordinate(0)),
                Op::DivideBy(4.0),
                Op::Binary(Binary::Subtract),
            ]
        );
        assert_eq!(expression.depth, 2);
    }
}
