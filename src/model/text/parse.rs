//! The parser of an expression: recursive descent over the grammar of the
//! [module docs](super), one function per precedence level (precedence climbing written
//! out), into an arena of [`Node`]s.

use super::error::TextError;
use super::tree::{
    Base, Binary, CONSTANT_NAMES, FUNCTION_NAMES, Function, Index, MAX_NESTING, MAX_NODES, Names,
    Node, Site, Symbol,
};

/// The largest integer of an index or a sum's bound (far from overflowing any sum of them).
const MAX_INDEX: i64 = 1 << 40;

/// A parsed expression: the arena of its nodes, its root, and its indexed sums.
pub struct Tree {
    /// The nodes, each after its children.
    pub nodes: Vec<Node>,
    /// The root.
    pub root: usize,
    /// The sums `sum(i, lower, upper, body)`, in the order they were read.
    pub sums: Vec<SumCall>,
}

/// One `sum(i, lower, upper, body)`: its body's root and bounds. In the arena the sum stands
/// as the number 0 at `placeholder` (the chains take the sums apart from the rest).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SumCall {
    /// The node standing for the sum.
    pub placeholder: usize,
    /// The root of the body.
    pub body: usize,
    /// The first index.
    pub lower: Index,
    /// The last index.
    pub upper: Index,
    /// Column of `sum`, in characters from 1.
    pub column: usize,
}

/// Parse `text`, the field `field` (named in errors), with the symbols of `names`.
pub fn parse(text: &str, field: &str, names: &Names<'_>) -> Result<Tree, TextError> {
    let mut parser = Parser {
        text,
        field,
        names,
        position: 0,
        nodes: Vec::new(),
        nesting: 0,
        sums: Vec::new(),
        index: None,
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
    Ok(Tree {
        nodes: parser.nodes,
        root,
        sums: parser.sums,
    })
}

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
    /// The sums read so far.
    pub sums: Vec<SumCall>,
    /// The index of the sum whose body is being read.
    pub index: Option<&'a str>,
}

/// Where an [`Index`] is read, which decides what it may be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum IndexRole {
    /// In `q[...]` inside a sum's body: `i + c`.
    Relative,
    /// In `q[...]` outside sums: `c` or `n + c`.
    Constant,
    /// A sum's bound: `c` or `n + c`.
    Bound,
}

impl<'a> Parser<'a> {
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

    /// An identifier starting at byte `start`.
    fn identifier(&self, start: usize) -> &'a str {
        let rest = &self.text[start..];
        let length = rest
            .find(|c: char| !(c.is_alphanumeric() || c == '_'))
            .unwrap_or(rest.len());
        &rest[..length]
    }

    /// Skip spaces and consume `c` if it comes next; else stay where the parser stood.
    fn eat_after_name(&mut self, c: char) -> bool {
        let save = self.position;
        let found = self.eat(c);
        if !found {
            self.position = save;
        }
        found
    }

    /// A name: a symbol, a constant, a function applied to its arguments, an indexed
    /// coordinate `q[...]` or a sum `sum(i, lower, upper, body)`.
    pub fn name(&mut self, start: usize) -> Result<usize, TextError> {
        let name = self.identifier(start);
        self.position = start + name.len();
        if self.eat_after_name('(') {
            if name == "sum" {
                return self.sum_call(start);
            }
            return self.call(name, start);
        }
        if self.eat_after_name('[') {
            return self.site(name, start);
        }
        if let Some(symbol) = self.names.symbol(name) {
            return self.push(Node::Symbol(symbol));
        }
        if self.names.family(name).is_some() {
            return Err(self.indexing(
                start,
                name,
                format!(
                    "'{name}' is an indexed coordinate: write {name}[i], {name}[i+1], {name}[1]"
                ),
            ));
        }
        if self.index == Some(name) {
            return Err(self.indexing(
                start,
                name,
                format!(
                    "the index '{name}' of a sum is read only inside brackets, as in q[{name}+1]"
                ),
            ));
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

    /// An error about indices or sums at byte `start`, at the symbol `symbol`.
    fn indexing(&self, start: usize, symbol: &str, message: String) -> TextError {
        TextError::Indexing {
            field: self.field.into(),
            column: self.column(start),
            symbol: symbol.into(),
            message,
        }
    }

    /// `name[index]` (`name` at byte `start`), after its '['.
    fn site(&mut self, name: &str, start: usize) -> Result<usize, TextError> {
        let Some((family, velocity)) = self.names.family(name) else {
            let message = if self.names.families.is_empty() {
                format!("'{name}' is not indexed: the model declares no indexed coordinates")
            } else {
                format!(
                    "'{name}' is not an indexed coordinate (indexed: {})",
                    self.names.families.join(", ")
                )
            };
            return Err(self.indexing(start, name, message));
        };
        let role = if self.index.is_some() {
            IndexRole::Relative
        } else {
            IndexRole::Constant
        };
        let index = self.index_expression(role, ']')?;
        self.eat(']');
        self.push(Node::Symbol(Symbol::Site(Site {
            family,
            velocity,
            index,
        })))
    }

    /// An index or a bound, `c`, `n + c` or `i + c`, written with integers, the size n and
    /// the sum's index i, added and subtracted in any order, up to `closing` (not consumed);
    /// what it may be depends on `role`.
    fn index_expression(&mut self, role: IndexRole, closing: char) -> Result<Index, TextError> {
        self.skip_space();
        let start = self.position;
        let (mut sum_coefficient, mut size_coefficient, mut offset) = (0i64, 0i64, 0i64);
        let mut sign = if self.eat('-') {
            -1
        } else {
            self.eat('+');
            1
        };
        loop {
            self.skip_space();
            let at = self.position;
            match self.peek_char() {
                Some(c) if c.is_ascii_digit() => {
                    let digits = self.text[at..]
                        .find(|c: char| !c.is_ascii_digit())
                        .map_or(&self.text[at..], |end| &self.text[at..at + end]);
                    self.position += digits.len();
                    let value = digits
                        .parse::<i64>()
                        .ok()
                        .filter(|value| *value <= MAX_INDEX)
                        .ok_or_else(|| {
                            self.indexing(
                                at,
                                digits,
                                format!("an index or bound beyond {MAX_INDEX}"),
                            )
                        })?;
                    offset += sign * value;
                }
                Some(c) if c.is_alphabetic() || c == '_' => {
                    let name = self.identifier(at);
                    self.position += name.len();
                    if Some(name) == self.index {
                        sum_coefficient += sign;
                    } else if Some(name) == self.names.size {
                        size_coefficient += sign;
                    } else {
                        let mut allowed = vec!["integers"];
                        allowed.extend(self.names.size);
                        allowed.extend(self.index);
                        return Err(self.indexing(
                            at,
                            name,
                            format!(
                                "an index or bound is made of {} with + and -",
                                allowed.join(", ")
                            ),
                        ));
                    }
                }
                _ => return Err(self.index_error(start, role, closing)),
            }
            if offset.abs() > MAX_INDEX || sum_coefficient.abs() > 1 || size_coefficient.abs() > 1 {
                return Err(self.index_error(start, role, closing));
            }
            sign = if self.eat('+') {
                1
            } else if self.eat('-') {
                -1
            } else {
                break;
            };
        }
        let base = match (sum_coefficient, size_coefficient) {
            (0, 0) => Base::Zero,
            (0, 1) => Base::Size,
            (1, 0) => Base::Sum,
            _ => return Err(self.index_error(start, role, closing)),
        };
        let fits = match role {
            IndexRole::Relative => base == Base::Sum,
            IndexRole::Constant | IndexRole::Bound => base != Base::Sum,
        };
        self.skip_space();
        if !fits || self.peek_char() != Some(closing) {
            return Err(self.index_error(start, role, closing));
        }
        Ok(Index { base, offset })
    }

    /// The error of an index (or bound) from byte `start` up to `closing` (or the end) that is
    /// not what `role` allows.
    fn index_error(&self, start: usize, role: IndexRole, closing: char) -> TextError {
        let size = self.names.size.unwrap_or("n");
        let index = self.index.unwrap_or("i");
        let message = match role {
            IndexRole::Relative => format!(
                "inside sum({index}, ...) an index is {index} plus or minus an integer \
                 ({index}, {index}+1, {index}-2): a term reads its neighbours only"
            ),
            IndexRole::Constant => format!(
                "outside a sum an index is an integer or {size} plus or minus an integer (1, {size}, \
                 {size}-1)"
            ),
            IndexRole::Bound => format!(
                "a sum's bound is an integer or {size} plus or minus an integer (0, 1, {size}, {size}-1)"
            ),
        };
        let end = self.text[start..]
            .find(closing)
            .map_or(self.text.len(), |end| start + end);
        self.indexing(start, self.text[start..end].trim(), message)
    }

    /// `sum(i, lower, upper, body)` (`sum` at byte `start`), after its '('.
    fn sum_call(&mut self, start: usize) -> Result<usize, TextError> {
        let open = self.position - 1;
        if self.names.families.is_empty() {
            return Err(self.indexing(
                start,
                "sum",
                "sum(i, lower, upper, body) needs indexed coordinates (coordinates = \
                 [\"q[1..n]\"])"
                    .into(),
            ));
        }
        if self.index.is_some() {
            return Err(self.indexing(
                start,
                "sum",
                "a sum inside a sum: a chain's terms are one sum deep".into(),
            ));
        }
        self.enter()?;
        self.skip_space();
        let at = self.position;
        let index = self.identifier(at);
        self.position += index.len();
        let taken = self.names.symbol(index).is_some()
            || self.names.family(index).is_some()
            || Some(index) == self.names.size
            || FUNCTION_NAMES.contains(&index)
            || CONSTANT_NAMES.contains(&index)
            || index == "sum";
        let identifier = index
            .chars()
            .next()
            .is_some_and(|c| c.is_alphabetic() || c == '_');
        if !identifier || taken {
            return Err(self.indexing(
                at,
                index,
                "the first argument of sum is a new name for its index, as in sum(i, 1, n, ...)"
                    .into(),
            ));
        }
        let mut bounds = [Index {
            base: Base::Zero,
            offset: 0,
        }; 2];
        for bound in &mut bounds {
            if !self.eat(',') {
                return Err(self.syntax(
                    self.position,
                    "sum takes four arguments: sum(i, lower, upper, body)".into(),
                ));
            }
            *bound = self.index_expression(IndexRole::Bound, ',')?;
        }
        if !self.eat(',') {
            return Err(self.syntax(
                self.position,
                "sum takes four arguments: sum(i, lower, upper, body)".into(),
            ));
        }
        self.index = Some(index);
        let body = self.sum()?;
        self.index = None;
        if !self.eat(')') {
            return Err(self.unclosed(open));
        }
        self.nesting -= 1;
        let placeholder = self.push(Node::Number(0.0))?;
        self.sums.push(SumCall {
            placeholder,
            body,
            lower: bounds[0],
            upper: bounds[1],
            column: self.column(start),
        });
        Ok(placeholder)
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
