//! What the structure of an expression shows about L: whether t appears, how q̇ appears
//! ([`VelocityForm`]), and for a constant-mass L the constant coefficients of its quadratic
//! form ([`Polynomial`]).

use super::tree::{Binary, Node, Symbol};

/// How L depends on q̇, as far as the expression's structure shows: a sum of a part free of
/// q̇ (`free`), a part linear in q̇ and a quadratic form in q̇, the last two with constant
/// coefficients; anything else is `None` (general).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct VelocityForm {
    /// The part free of q̇: absent, constant (numbers and parameters), or depending on t, q.
    free: Free,
    /// Whether terms linear in q̇ (constant coefficients) appear.
    pub linear: bool,
    /// Whether terms quadratic in q̇ (constant coefficients) appear.
    pub quadratic: bool,
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

    /// Whether the expression is ½q̇ᵀMq̇ − V(t, q) with M constant, or a part of such an L
    /// (a sum's body, which may hold no q̇): no term linear in q̇, and the quadratic terms, if
    /// any, with constant coefficients (as a [`VelocityForm`] has them).
    pub fn fits_constant_mass(self) -> bool {
        !self.linear
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
    /// Whether the expression is, by its structure, a sum of parts each free of q̇ or free of
    /// (t, q) (constant factors allowed): for a Hamiltonian, whose momenta sit in q̇'s slot,
    /// H = T(p) + V(t, q).
    pub separable: bool,
    /// How q̇ appears (`None`: in a way the analysis does not follow).
    pub velocity: Option<VelocityForm>,
}

/// A polynomial of degree at most 2 in q̇ with constant coefficients, plus a part free of
/// q̇: what [`Expression::quadratic_form`] reads off a constant-mass L.
pub struct Polynomial {
    /// The part free of q̇: its value if it is constant, `None` if it depends on t or q.
    pub constant: Option<f64>,
    /// Coefficients of q̇ᵢ.
    pub linear: Vec<f64>,
    /// Coefficients of q̇ᵢq̇ⱼ, row-major n × n.
    pub quadratic: Vec<f64>,
    /// The structural degree in q̇ (0, 1 or 2), whatever the coefficients' values.
    pub degree: u8,
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
    pub fn of(nodes: &[Node], node: usize, parameters: &[f64], n: usize) -> Option<Polynomial> {
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

/// What the structure of the subtree at `root` shows.
pub fn properties(nodes: &[Node], root: usize) -> Properties {
    Properties {
        time: nodes.contains(&Node::Symbol(Symbol::Time)),
        separable: separable(nodes, root),
        velocity: velocity_form(nodes, root),
    }
}

/// Which variables the subtree at `node` reads: (q̇, t or q).
fn reads(nodes: &[Node], node: usize) -> (bool, bool) {
    match nodes[node] {
        Node::Number(_) | Node::Symbol(Symbol::Parameter(_)) => (false, false),
        Node::Symbol(Symbol::Velocity(_)) => (true, false),
        Node::Symbol(Symbol::Site(site)) => (site.velocity, !site.velocity),
        Node::Symbol(_) => (false, true),
        Node::Negate(a) | Node::PowerInteger(a, _) | Node::Call(_, a) => reads(nodes, a),
        Node::Binary(_, a, b) => {
            let (x, y) = (reads(nodes, a), reads(nodes, b));
            (x.0 || y.0, x.1 || y.1)
        }
    }
}

/// [`Properties::separable`] of the subtree at `node`.
fn separable(nodes: &[Node], node: usize) -> bool {
    let constant = |node| reads(nodes, node) == (false, false);
    match nodes[node] {
        Node::Binary(Binary::Add | Binary::Subtract, a, b) => {
            separable(nodes, a) && separable(nodes, b)
        }
        Node::Negate(a) => separable(nodes, a),
        Node::Binary(Binary::Multiply, a, b) if constant(a) => separable(nodes, b),
        Node::Binary(Binary::Multiply | Binary::Divide, a, b) if constant(b) => separable(nodes, a),
        _ => reads(nodes, node) != (true, true),
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
