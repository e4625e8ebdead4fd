//! The parse tree of an expression: its nodes, the symbols, operations and functions they
//! name, and the limits on its size.

use crate::scalar::Scalar;

/// Most numbers, names and operations in one expression (it bounds the recursion of the
/// folding and analysis over the tree, whatever the input).
pub const MAX_NODES: usize = 2048;

/// Most nested parentheses, function calls, unary signs and powers inside one another (it
/// bounds the parser's recursion, whatever the input).
pub const MAX_NESTING: usize = 200;

/// The functions of the grammar, by name.
pub const FUNCTION_NAMES: &[&str] = &[
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "exp", "ln",
    "log", "sqrt", "abs",
];

/// The named constants of the grammar.
pub const CONSTANT_NAMES: &[&str] = &["pi", "e"];

/// A function of one argument.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Function {
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
    pub fn named(name: &str) -> Option<Function> {
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
    pub fn apply<D: Scalar>(self, x: D) -> D {
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
    /// A coordinate or velocity of an indexed family, `q[i+1]` or `vq[n]` (the chains of
    /// [`super::chain`]: rewritten to a term's slots, as `Coordinate` and `Velocity`, before
    /// anything is compiled or analysed).
    Site(Site),
}

/// `q[index]` (or `vq[index]`): which family, coordinate or velocity, and at which index.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Site {
    /// The family, in the order of the declared coordinates.
    pub family: usize,
    /// Whether the velocity `vq[...]` is read.
    pub velocity: bool,
    /// The index.
    pub index: Index,
}

/// An index or a bound of a sum: `base + offset`, an integer written `c`, `n + c` (n the size
/// parameter) or, inside `sum(i, ...)`, `i + c`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Index {
    /// What the offset is added to.
    pub base: Base,
    /// The integer c.
    pub offset: i64,
}

/// What an [`Index`]'s offset is added to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Base {
    /// Nothing: the index is the integer c.
    Zero,
    /// The size parameter n.
    Size,
    /// The index of the enclosing sum.
    Sum,
}

impl Index {
    /// The value for the size `n` (`None` for an index relative to a sum's).
    pub fn resolve(self, n: usize) -> Option<i64> {
        match self.base {
            Base::Zero => Some(self.offset),
            // n ≤ the largest size, far below 2⁶³.
            Base::Size => Some(n as i64 + self.offset),
            Base::Sum => None,
        }
    }
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
    /// The indexed families (`q` of `q[1..n]`) and, after them, their velocities (`vq`):
    /// names read with an index, `q[i+1]`. Empty for a model without (then `sum` is unknown).
    pub families: &'a [&'static str],
    /// The size parameter n of the families (`None` without families).
    pub size: Option<&'static str>,
}

impl Names<'_> {
    /// The family named `name` (coordinate or velocity), if any, as (family, velocity).
    pub fn family(&self, name: &str) -> Option<(usize, bool)> {
        let count = self.families.len() / 2;
        let position = self.families.iter().position(|known| *known == name)?;
        if position >= count && !self.phase_space {
            return None;
        }
        Some((position % count.max(1), position >= count))
    }
}

impl Names<'_> {
    /// The symbol named `name`, if any.
    pub fn symbol(&self, name: &str) -> Option<Symbol> {
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

    /// The known symbols, as listed in an error message (a family with `[...]`).
    pub fn known(&self) -> String {
        let mut names: Vec<String> = self.coordinates.iter().map(|s| s.to_string()).collect();
        let count = self.families.len() / 2;
        let indexed = |names: &[&str]| {
            names
                .iter()
                .map(|name| format!("{name}[...]"))
                .collect::<Vec<_>>()
        };
        names.extend(indexed(&self.families[..count]));
        if self.phase_space {
            names.extend(self.velocities.iter().map(|s| s.to_string()));
            names.extend(indexed(&self.families[count..]));
            names.push("t".into());
        }
        names.extend(self.parameters.iter().map(|s| s.to_string()));
        names.join(", ")
    }
}

/// A binary operation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Binary {
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
    pub fn apply<D: Scalar>(self, x: D, y: D) -> D {
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
pub enum Node {
    Number(f64),
    Symbol(Symbol),
    Negate(usize),
    /// xⁿ, n an integer literal.
    PowerInteger(usize, i32),
    Call(Function, usize),
    Binary(Binary, usize, usize),
}
