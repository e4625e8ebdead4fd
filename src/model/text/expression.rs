//! One expression of a text model: parsed once ([`Expression::parse`], with the parser of
//! [`super::parse`]), compiled for given parameter values into a postfix [`Tape`]
//! ([`Expression::compile`]: constants folded, instructions fused), and evaluated on a
//! fixed-size array (no allocation per evaluation), generic over [`Scalar`].

use super::error::TextError;
use super::parse::parse;
use super::structure::{Polynomial, Properties, properties};
use super::tree::{Binary, Function, Names, Node, Symbol};
use crate::scalar::Scalar;

/// Most values an expression's tape keeps on its stack at once; deeper expressions are an
/// error ([`TextError::TooDeep`]). A sum or product of any length needs two slots; only
/// nesting to the right (`a*(b*(c*...))`) needs more.
pub const MAX_STACK: usize = 64;

/// One instruction of the postfix tape. The top of the stack is kept apart, in a local
/// (the accumulator): a load pushes the accumulator and replaces it, a unary operation
/// changes it in place, a binary one combines it with the value it pops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Op {
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
        // Without indexed families the parser reads no sum: the tree is the expression.
        let tree = parse(text, field, names)?;
        Expression::from_tree(tree.nodes, tree.root, field, names.parameters.len())
    }

    /// The expression of the parse tree `nodes` at `root` (no [`Symbol::Site`] left), with
    /// `parameter_count` parameters, as the field `field`.
    ///
    /// # Errors
    /// [`TextError::TooDeep`] if its tape may need more than [`MAX_STACK`] values at once.
    pub fn from_tree(
        nodes: Vec<Node>,
        root: usize,
        field: &str,
        parameter_count: usize,
    ) -> Result<Expression, TextError> {
        let expression = Expression {
            properties: properties(&nodes, root),
            nodes,
            root,
        };
        // The deepest tape for any parameter values: NaN is neither 0 nor 1, so no
        // instruction folds away for it (x + 0 is x, 1/x a reciprocal; for other values the
        // tape is as deep or less).
        let parameters = vec![f64::NAN; parameter_count];
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

    /// Whether any coordinate appears in the expression.
    pub fn uses_coordinates(&self) -> bool {
        self.nodes
            .iter()
            .any(|node| matches!(node, Node::Symbol(Symbol::Coordinate(_))))
    }

    /// Whether the velocity of coordinate `i` appears in the expression.
    pub fn uses_velocity(&self, i: usize) -> bool {
        self.nodes
            .iter()
            .any(|node| matches!(node, Node::Symbol(Symbol::Velocity(j)) if *j == i))
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

/// A constant-mass L = ½q̇ᵀMq̇ + U(t, q) in two parts.
#[derive(Debug, Clone, PartialEq)]
pub struct Split {
    /// The tape of U(t, q) = L(t, q, 0).
    potential: Tape,
    /// The terms (i, j, c) of ½q̇ᵀMq̇ = Σ c q̇ᵢq̇ⱼ (i ≤ j, c ≠ 0), evaluated without a tape.
    kinetic: Vec<(usize, usize, f64)>,
}

impl Split {
    /// `expression` of `n` coordinates with `parameters` in two parts, if its structure is
    /// constant-mass (no term linear in q̇, constant coefficients of the quadratic ones).
    pub fn of(expression: &Expression, parameters: &[f64], n: usize) -> Option<Split> {
        expression
            .properties()
            .velocity
            .filter(|form| form.fits_constant_mass())?;
        let q = expression.quadratic_form(parameters, n)?;
        let mut kinetic = Vec::new();
        for i in 0..n {
            for j in i..n {
                let c = if i == j {
                    q[i * n + i]
                } else {
                    q[i * n + j] + q[j * n + i]
                };
                if c != 0.0 {
                    kinetic.push((i, j, c));
                }
            }
        }
        Some(Split {
            potential: expression.compile(parameters, Velocities::Zero),
            kinetic,
        })
    }

    /// The tape of U(t, q), the part free of q̇.
    pub fn potential(&self) -> &Tape {
        &self.potential
    }

    /// ½q̇ᵀMq̇ (a sum of products, without a tape) plus U(t, q).
    #[inline]
    pub fn evaluate<D: Scalar>(&self, t: D, q: &[D], v: &[D]) -> D {
        let mut sum = self.potential.evaluate(t, q, v);
        for &(i, j, c) in &self.kinetic {
            sum += v[i] * v[j] * c;
        }
        sum
    }
}

/// An expression compiled for given parameter values: a postfix program of [`Op`]s.
#[derive(Debug, Clone, PartialEq)]
pub struct Tape {
    ops: Vec<Op>,
    depth: usize,
}

impl Tape {
    /// The instructions.
    pub fn ops(&self) -> &[Op] {
        &self.ops
    }

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
            Symbol::Site(_) => unreachable!("sites are rewritten to slots before compiling"),
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
                Op::PowerInteger(n) => power_integer(x, n),
                // The square root of norms is inlined: as a call it cost a quarter of a
                // Kepler run.
                Op::Call(Function::Sqrt) => x.sqrt(),
                Op::Call(function) => function.apply(x),
                Op::Binary(binary) => {
                    top -= 1;
                    arithmetic(binary, stack[top], x)
                }
                Op::WithSymbol(binary, symbol) => arithmetic(binary, x, fetch(symbol)),
                Op::WithSquare(binary, symbol) => {
                    let value = fetch(symbol);
                    arithmetic(binary, x, value * value)
                }
            };
        }
        accumulator
    }
}

/// x ∘ y with the four arithmetic operations inlined into the tape's loop (the powers and
/// atan2 are calls).
#[inline(always)]
fn arithmetic<D: Scalar>(binary: Binary, x: D, y: D) -> D {
    match binary {
        Binary::Add => x + y,
        Binary::Subtract => x - y,
        Binary::Multiply => x * y,
        Binary::Divide => x / y,
        _ => binary.apply(x, y),
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

/// The largest |n| for which num-dual's `powi` is used: its derivative factors n(n − 1) and
/// n(n − 1)(n − 2) are computed in `i32` and overflow beyond about 1290.
const POWI_LIMIT: u32 = 1000;

/// xⁿ for an integer exponent n, with exact derivatives for every n: num-dual's `powi` up to
/// [`POWI_LIMIT`], beyond it by repeated squaring (at most 62 products, no integer
/// arithmetic that could overflow). A huge power of |x| > 1 is infinite, which the run
/// reports as a non-finite state.
fn power_integer<D: Scalar>(x: D, n: i32) -> D {
    if n.unsigned_abs() <= POWI_LIMIT {
        return x.powi(n);
    }
    let (mut base, mut power, mut exponent) = (x, D::one(), n.unsigned_abs());
    while exponent > 0 {
        if exponent & 1 == 1 {
            power *= base;
        }
        base = base * base;
        exponent >>= 1;
    }
    if n < 0 { power.recip() } else { power }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::text::tree::MAX_NODES;

    #[test]
    fn huge_integer_powers_have_exact_derivatives() {
        // d/dx xⁿ = n xⁿ⁻¹, d²/dx² = n(n − 1) xⁿ⁻²: at x = 1 the factors themselves, which
        // num-dual's powi computes in i32 and overflows for n ≳ 1290.
        for n in [3, 1000, 1001, 99_999, 2_000_000_000, -99_999] {
            let (value, first, second) = num_dual::second_derivative(|x| power_integer(x, n), 1.0);
            let n = f64::from(n);
            assert_eq!(value, 1.0);
            assert!((first - n).abs() <= 1e-12 * n.abs(), "{n}: {first}");
            assert!(
                (second - n * (n - 1.0)).abs() <= 1e-9 * (n * n).abs(),
                "{n}: {second}"
            );
        }
        // Away from 1 the value and its derivatives follow the closed forms.
        let x: f64 = 1.0 - 1e-5;
        let (value, first, _) = num_dual::second_derivative(|x| power_integer(x, 100_001), x);
        let exact = x.powi(100_001);
        assert!((value - exact).abs() <= 1e-11 * exact);
        assert!((first - 100_001.0 * x.powi(100_000)).abs() <= 1e-9 * first.abs());
        // A huge power of |x| > 1 overflows to infinity, never to a wrapped garbage factor.
        let (value, _, _) = num_dual::second_derivative(|x| power_integer(x, i32::MAX), 2.0);
        assert_eq!(value, f64::INFINITY);
    }

    const COORDINATES: [&str; 2] = ["x", "y"];
    const VELOCITIES: [&str; 2] = ["vx", "vy"];
    const PARAMETERS: [&str; 1] = ["mu"];

    fn names() -> Names<'static> {
        Names {
            coordinates: &COORDINATES,
            velocities: &VELOCITIES,
            parameters: &PARAMETERS,
            phase_space: true,
            families: &[],
            size: None,
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
                .is_some_and(|form| form.quadratic && form.fits_constant_mass())
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
