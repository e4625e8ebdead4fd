//! The parser of an expression: recursive descent over the grammar of the
//! [module docs](super), one function per precedence level (precedence climbing written
//! out), into an arena of [`Node`]s.

use super::TextError;
use super::tree::{Binary, FUNCTION_NAMES, Function, MAX_NESTING, MAX_NODES, Names, Node, Symbol};

/// The recursive-descent parser over `text`, building the arena `nodes`.
pub struct Parser<'a> {
    pub text: &'a str,
    pub field: &'a str,
    pub names: &'a Names<'a>,
    /// Byte offset of the next character.
    pub position: usize,
    pub nodes: Vec<Node>,
    /// Current nesting of the recursion.
    pub nesting: usize,
}

impl Parser<'_> {
    /// The 1-based character column of the byte offset `offset`.
    pub fn column(&self, offset: usize) -> usize {
        self.text[..offset].chars().count() + 1
    }

    /// A syntax error at byte offset `offset`.
    pub fn syntax(&self, offset: usize, message: String) -> TextError {
        TextError::Syntax {
            field: self.field.into(),
            column: self.column(offset),
            message,
        }
    }

    pub fn peek_char(&self) -> Option<char> {
        self.text[self.position..].chars().next()
    }

    pub fn skip_space(&mut self) {
        while let Some(c) = self.peek_char().filter(|c| c.is_whitespace()) {
            self.position += c.len_utf8();
        }
    }

    /// Skip spaces; consume `c` if it comes next.
    pub fn eat(&mut self, c: char) -> bool {
        self.skip_space();
        if self.peek_char() == Some(c) {
            self.position += c.len_utf8();
            true
        } else {
            false
        }
    }

    /// Add `node` to the arena, or fail beyond [`MAX_NODES`].
    pub fn push(&mut self, node: Node) -> Result<usize, TextError> {
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
    pub fn enter(&mut self) -> Result<(), TextError> {
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
    pub fn sum(&mut self) -> Result<usize, TextError> {
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
    pub fn product(&mut self) -> Result<usize, TextError> {
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
    pub fn unary(&mut self) -> Result<usize, TextError> {
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
    pub fn power(&mut self) -> Result<usize, TextError> {
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
    pub fn atom(&mut self) -> Result<usize, TextError> {
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
    pub fn unclosed(&self, start: usize) -> TextError {
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
    pub fn number(&mut self, start: usize) -> Result<usize, TextError> {
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
    pub fn name(&mut self, start: usize) -> Result<usize, TextError> {
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
    pub fn call(&mut self, name: &str, start: usize) -> Result<usize, TextError> {
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
