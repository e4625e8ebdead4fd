//! A chain's terms on batches of sites: the value ℓ and the force ∂ℓ/∂q of one kind of term,
//! compiled from its [`Tape`] into straight-line programs (the force by reverse-mode
//! automatic differentiation), each run on [`LANES`] sites at once. The same programs give
//! a constant-mass text model's force on many points at once ([`Program::forces`]: SVI's
//! quadrature points, one a lane).
//!
//! # Why
//!
//! Assembled term by term ([`crate::model::local::force_by_terms`]), a chain's force runs
//! each term's tape once per slot in forward-mode dual numbers: for FPUT two interpreted
//! sweeps of fifteen instructions per spring, against a handful of multiplications in a
//! model written in Rust; its value (the energy diagnostic, at every step) one interpreted
//! sweep. Here each kind of term is compiled once, and its programs run over [`LANES`] sites
//! of that kind together: every instruction is a loop over the lanes, which the compiler
//! vectorises, so the cost of interpreting it is paid once per batch instead of once per
//! term.
//!
//! # How
//!
//! 1. The postfix tape becomes a list of instructions in static single assignment, equal
//!    instructions shared (`q[i+1] - q[i]`, written three times in FPUT, is computed once).
//! 2. For the force, reverse mode from the end: each instruction adds its operands' share of
//!    its adjoint, ∂ℓ/∂x = Σ (∂ℓ/∂y)(∂y/∂x), as new instructions. Adjoints that are
//!    constants stay numbers (the adjoint of ℓ is 1, of `0.5*d^2` then 0.5) and constant
//!    factors of the others are carried along, not computed (−(1/s)² · ½(1/s) is one
//!    product with the factor −½), so the derivative of a polynomial folds to the
//!    polynomial's derivative: FPUT's spring force is ±(d + α d² + β d³),
//!    d = q_{i+1} − q_i, in nine instructions with the two loads — against two sweeps of
//!    fifteen on dual numbers; Kepler's in eleven.
//! 3. What the outputs (the value, or the force on each slot) do not need is dropped — ℓ's
//!    value from the force —, and the values are given registers, reused once dead: at most
//!    [`MAX_REGISTERS`] of [`LANES`] numbers, a register file on the stack. A kind that
//!    needs more runs term by term.
//!
//! The programs compute in another order than the tape and the dual numbers do: they agree
//! to round-off (tested), not bit for bit.

use std::collections::HashMap;

use super::expression::{Op, Tape};
use super::tree::{Binary, Function, Symbol};

/// Sites evaluated together: the length of a register.
pub const LANES: usize = 32;

/// Most registers of a program (8 KB of registers on the stack).
pub const MAX_REGISTERS: usize = 32;

/// A register file: [`MAX_REGISTERS`] registers of [`LANES`] numbers.
pub type Registers = [[f64; LANES]; MAX_REGISTERS];

/// One instruction, its operands by value (in the building) or register (in a program).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Instruction {
    Number(f64),
    Coordinate(usize),
    Velocity(usize),
    Time,
    Negate(usize),
    Scale(usize, f64),
    Shift(usize, f64),
    DivideBy(usize, f64),
    Reciprocal(usize),
    Square(usize),
    PowerInteger(usize, i32),
    Call(Function, usize),
    /// x ↦ −1 for x < 0, else 1: the derivative of `abs` as the dual numbers take it.
    Sign(usize),
    Binary(Binary, usize, usize),
}

impl Instruction {
    /// The operands.
    fn operands(self) -> [Option<usize>; 2] {
        match self {
            Instruction::Number(_)
            | Instruction::Coordinate(_)
            | Instruction::Velocity(_)
            | Instruction::Time => [None, None],
            Instruction::Negate(x)
            | Instruction::Scale(x, _)
            | Instruction::Shift(x, _)
            | Instruction::DivideBy(x, _)
            | Instruction::Reciprocal(x)
            | Instruction::Square(x)
            | Instruction::PowerInteger(x, _)
            | Instruction::Call(_, x)
            | Instruction::Sign(x) => [Some(x), None],
            Instruction::Binary(_, x, y) => [Some(x), Some(y)],
        }
    }

    /// The instruction with its operands renamed by `rename`.
    fn renamed(self, rename: impl Fn(usize) -> usize) -> Instruction {
        match self {
            Instruction::Negate(x) => Instruction::Negate(rename(x)),
            Instruction::Scale(x, c) => Instruction::Scale(rename(x), c),
            Instruction::Shift(x, c) => Instruction::Shift(rename(x), c),
            Instruction::DivideBy(x, c) => Instruction::DivideBy(rename(x), c),
            Instruction::Reciprocal(x) => Instruction::Reciprocal(rename(x)),
            Instruction::Square(x) => Instruction::Square(rename(x)),
            Instruction::PowerInteger(x, n) => Instruction::PowerInteger(rename(x), n),
            Instruction::Call(function, x) => Instruction::Call(function, rename(x)),
            Instruction::Sign(x) => Instruction::Sign(rename(x)),
            Instruction::Binary(binary, x, y) => Instruction::Binary(binary, rename(x), rename(y)),
            leaf => leaf,
        }
    }

    /// A key equal for equal instructions (numbers by their bits).
    fn key(self) -> (u8, usize, usize, u64) {
        let none = usize::MAX;
        match self {
            Instruction::Number(c) => (0, none, none, c.to_bits()),
            Instruction::Coordinate(u) => (1, u, none, 0),
            Instruction::Velocity(u) => (2, u, none, 0),
            Instruction::Time => (3, none, none, 0),
            Instruction::Negate(x) => (4, x, none, 0),
            Instruction::Scale(x, c) => (5, x, none, c.to_bits()),
            Instruction::Shift(x, c) => (6, x, none, c.to_bits()),
            Instruction::DivideBy(x, c) => (7, x, none, c.to_bits()),
            Instruction::Reciprocal(x) => (8, x, none, 0),
            Instruction::Square(x) => (9, x, none, 0),
            Instruction::PowerInteger(x, n) => (10, x, none, u64::from(n as u32)),
            Instruction::Call(function, x) => (11, x, none, function as u64),
            Instruction::Sign(x) => (12, x, none, 0),
            Instruction::Binary(binary, x, y) => (13, x, y, binary as u64),
        }
    }
}

/// An adjoint while the program is built: zero, a number, or a number times a value (the
/// factor carried along, not computed: a chain of scalings folds into one number, applied
/// where a sum needs it or when the force is written).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Adjoint {
    Zero,
    Constant(f64),
    Value(f64, usize),
}

/// Instructions in static single assignment, equal ones shared.
#[derive(Default)]
struct Builder {
    instructions: Vec<Instruction>,
    known: HashMap<(u8, usize, usize, u64), usize>,
}

impl Builder {
    /// The value of `instruction`: an equal earlier one's, or a new one.
    fn emit(&mut self, instruction: Instruction) -> usize {
        *self.known.entry(instruction.key()).or_insert_with(|| {
            self.instructions.push(instruction);
            self.instructions.len() - 1
        })
    }

    /// xⁿ: x, its square, its reciprocal, or an integer power (one instruction, whose
    /// derivative n xⁿ⁻¹ is one more: FPUT's d⁴ differentiates to the d³ it has already).
    fn power(&mut self, x: usize, n: i32) -> usize {
        match n {
            1 => x,
            2 => self.emit(Instruction::Square(x)),
            -1 => self.emit(Instruction::Reciprocal(x)),
            _ => self.emit(Instruction::PowerInteger(x, n)),
        }
    }

    /// a · x.
    fn times(&mut self, a: Adjoint, x: usize) -> Adjoint {
        match a {
            Adjoint::Zero => Adjoint::Zero,
            Adjoint::Constant(c) => Adjoint::Value(c, x),
            Adjoint::Value(c, a) => {
                Adjoint::Value(c, self.emit(Instruction::Binary(Binary::Multiply, a, x)))
            }
        }
    }

    /// a · b.
    fn product(&mut self, a: Adjoint, b: Adjoint) -> Adjoint {
        match b {
            Adjoint::Zero => Adjoint::Zero,
            Adjoint::Constant(c) => self.scaled(a, c),
            Adjoint::Value(c, x) => {
                let share = self.times(a, x);
                self.scaled(share, c)
            }
        }
    }

    /// c · a.
    fn scaled(&mut self, a: Adjoint, c: f64) -> Adjoint {
        match a {
            Adjoint::Zero => Adjoint::Zero,
            Adjoint::Constant(d) => Adjoint::Constant(c * d),
            Adjoint::Value(d, x) => Adjoint::Value(c * d, x),
        }
    }

    /// The value c · x itself (an instruction unless c = 1).
    fn computed(&mut self, c: f64, x: usize) -> usize {
        match c {
            1.0 => x,
            -1.0 => self.emit(Instruction::Negate(x)),
            c => self.emit(Instruction::Scale(x, c)),
        }
    }

    /// a + b (c x + c y as c (x + y), c x − c y as c (x − y)).
    fn plus(&mut self, a: Adjoint, b: Adjoint) -> Adjoint {
        match (a, b) {
            (Adjoint::Zero, other) | (other, Adjoint::Zero) => other,
            (Adjoint::Constant(c), Adjoint::Constant(d)) => Adjoint::Constant(c + d),
            (Adjoint::Constant(c), Adjoint::Value(d, x))
            | (Adjoint::Value(d, x), Adjoint::Constant(c)) => {
                let x = self.computed(d, x);
                Adjoint::Value(1.0, self.emit(Instruction::Shift(x, c)))
            }
            (Adjoint::Value(c, x), Adjoint::Value(d, y)) if c == d => {
                Adjoint::Value(c, self.emit(Instruction::Binary(Binary::Add, x, y)))
            }
            (Adjoint::Value(c, x), Adjoint::Value(d, y)) if c == -d => {
                Adjoint::Value(c, self.emit(Instruction::Binary(Binary::Subtract, x, y)))
            }
            (Adjoint::Value(c, x), Adjoint::Value(d, y)) => {
                let (x, y) = (self.computed(c, x), self.computed(d, y));
                Adjoint::Value(1.0, self.emit(Instruction::Binary(Binary::Add, x, y)))
            }
        }
    }

    /// The values of `tape`'s instructions; the last is its result. `None` for a tape that
    /// reads what a compiled tape does not (a parameter, a site).
    fn forward(&mut self, tape: &Tape) -> Option<usize> {
        let load = |symbol: Symbol| match symbol {
            Symbol::Coordinate(u) => Some(Instruction::Coordinate(u)),
            Symbol::Velocity(u) => Some(Instruction::Velocity(u)),
            Symbol::Time => Some(Instruction::Time),
            Symbol::Parameter(_) | Symbol::Site(_) => None,
        };
        let mut stack: Vec<usize> = Vec::new();
        for op in tape.ops() {
            let value = match *op {
                Op::Number(c) => self.emit(Instruction::Number(c)),
                Op::Load(symbol) => self.emit(load(symbol)?),
                Op::LoadSquare(symbol) => {
                    let x = self.emit(load(symbol)?);
                    self.emit(Instruction::Square(x))
                }
                Op::Binary(binary) => {
                    let y = stack.pop()?;
                    let x = stack.pop()?;
                    self.emit(Instruction::Binary(binary, x, y))
                }
                Op::WithSymbol(binary, symbol) => {
                    let x = stack.pop()?;
                    let y = self.emit(load(symbol)?);
                    self.emit(Instruction::Binary(binary, x, y))
                }
                Op::WithSquare(binary, symbol) => {
                    let x = stack.pop()?;
                    let y = self.emit(load(symbol)?);
                    let y = self.emit(Instruction::Square(y));
                    self.emit(Instruction::Binary(binary, x, y))
                }
                unary => {
                    let x = stack.pop()?;
                    self.emit(match unary {
                        Op::Negate => Instruction::Negate(x),
                        Op::Scale(c) => Instruction::Scale(x, c),
                        Op::Shift(c) => Instruction::Shift(x, c),
                        Op::DivideBy(c) => Instruction::DivideBy(x, c),
                        Op::Reciprocal => Instruction::Reciprocal(x),
                        Op::Square => Instruction::Square(x),
                        Op::PowerInteger(n) => {
                            stack.push(self.power(x, n));
                            continue;
                        }
                        Op::Call(function) => Instruction::Call(function, x),
                        _ => return None,
                    })
                }
            };
            stack.push(value);
        }
        stack.pop()
    }

    /// The derivative of `function` at the value `x`, whose result is the value `y`.
    fn derivative(&mut self, function: Function, x: usize, y: usize) -> Adjoint {
        let value = |x: usize| Adjoint::Value(1.0, x);
        let one_minus_square = |builder: &mut Builder, z: usize| {
            let square = builder.emit(Instruction::Square(z));
            let negated = builder.emit(Instruction::Negate(square));
            builder.emit(Instruction::Shift(negated, 1.0))
        };
        match function {
            Function::Sin => value(self.emit(Instruction::Call(Function::Cos, x))),
            Function::Cos => Adjoint::Value(-1.0, self.emit(Instruction::Call(Function::Sin, x))),
            Function::Tan => {
                let square = self.emit(Instruction::Square(y));
                value(self.emit(Instruction::Shift(square, 1.0)))
            }
            Function::Asin | Function::Acos => {
                let root = one_minus_square(self, x);
                let root = self.emit(Instruction::Call(Function::Sqrt, root));
                let reciprocal = self.emit(Instruction::Reciprocal(root));
                match function {
                    Function::Asin => value(reciprocal),
                    _ => Adjoint::Value(-1.0, reciprocal),
                }
            }
            Function::Atan => {
                let square = self.emit(Instruction::Square(x));
                let denominator = self.emit(Instruction::Shift(square, 1.0));
                value(self.emit(Instruction::Reciprocal(denominator)))
            }
            Function::Sinh => value(self.emit(Instruction::Call(Function::Cosh, x))),
            Function::Cosh => value(self.emit(Instruction::Call(Function::Sinh, x))),
            Function::Tanh => value(one_minus_square(self, y)),
            Function::Exp => value(y),
            Function::Ln => value(self.emit(Instruction::Reciprocal(x))),
            Function::Sqrt => Adjoint::Value(0.5, self.emit(Instruction::Reciprocal(y))),
            Function::Abs => value(self.emit(Instruction::Sign(x))),
        }
    }

    /// The gradient of the value `output` with respect to the coordinates of `width` slots,
    /// by reverse mode over the instructions before it. `None` for an exponent that is not a
    /// number where one must be.
    fn reverse(&mut self, output: usize, width: usize) -> Option<Vec<Adjoint>> {
        let mut adjoints = vec![Adjoint::Zero; output + 1];
        adjoints[output] = Adjoint::Constant(1.0);
        let mut gradient = vec![Adjoint::Zero; width];
        for value in (0..=output).rev() {
            let a = adjoints[value];
            if a == Adjoint::Zero {
                continue;
            }
            let mut add = |builder: &mut Builder, to: usize, share: Adjoint| {
                adjoints[to] = builder.plus(adjoints[to], share);
            };
            match self.instructions[value] {
                Instruction::Number(_)
                | Instruction::Time
                | Instruction::Velocity(_)
                | Instruction::Sign(_) => {}
                Instruction::Coordinate(u) => gradient[u] = self.plus(gradient[u], a),
                Instruction::Negate(x) => {
                    let share = self.scaled(a, -1.0);
                    add(self, x, share);
                }
                Instruction::Scale(x, c) => {
                    let share = self.scaled(a, c);
                    add(self, x, share);
                }
                Instruction::Shift(x, _) => add(self, x, a),
                Instruction::DivideBy(x, c) => {
                    let share = match a {
                        Adjoint::Value(d, r) => Adjoint::Value(d / c, r),
                        Adjoint::Constant(d) => Adjoint::Constant(d / c),
                        Adjoint::Zero => Adjoint::Zero,
                    };
                    add(self, x, share);
                }
                Instruction::Reciprocal(x) => {
                    // d(1/x) = −(1/x)².
                    let square = self.emit(Instruction::Square(value));
                    let share = self.times(a, square);
                    let share = self.scaled(share, -1.0);
                    add(self, x, share);
                }
                Instruction::Square(x) => {
                    let share = self.scaled(a, 2.0);
                    let share = self.times(share, x);
                    add(self, x, share);
                }
                Instruction::PowerInteger(x, n) => {
                    let share = self.scaled(a, f64::from(n));
                    let share = match n - 1 {
                        0 => share,
                        m => {
                            let power = self.power(x, m);
                            self.times(share, power)
                        }
                    };
                    add(self, x, share);
                }
                Instruction::Call(function, x) => {
                    let derivative = self.derivative(function, x, value);
                    let share = self.product(a, derivative);
                    add(self, x, share);
                }
                Instruction::Binary(binary, x, y) => {
                    for (to, share) in self.binary_shares(binary, x, y, value, a)? {
                        add(self, to, share);
                    }
                }
            }
        }
        Some(gradient)
    }

    /// The shares of the adjoint `a` of `value` = x ∘ y that go to x and to y.
    fn binary_shares(
        &mut self,
        binary: Binary,
        x: usize,
        y: usize,
        value: usize,
        a: Adjoint,
    ) -> Option<[(usize, Adjoint); 2]> {
        Some(match binary {
            Binary::Add => [(x, a), (y, a)],
            Binary::Subtract => [(x, a), (y, self.scaled(a, -1.0))],
            Binary::Multiply => [(x, self.times(a, y)), (y, self.times(a, x))],
            Binary::Divide => {
                // d(x/y) = dx/y − (x/y) dy/y.
                let reciprocal = self.emit(Instruction::Reciprocal(y));
                let to_x = self.times(a, reciprocal);
                let to_y = self.times(to_x, value);
                [(x, to_x), (y, self.scaled(to_y, -1.0))]
            }
            Binary::Power => {
                // x^y = exp(y ln x): d = y x^y / x dx + x^y ln x dy.
                let reciprocal = self.emit(Instruction::Reciprocal(x));
                let to_x = self.times(a, y);
                let to_x = self.times(to_x, value);
                let to_x = self.times(to_x, reciprocal);
                let logarithm = self.emit(Instruction::Call(Function::Ln, x));
                let to_y = self.times(a, value);
                [(x, to_x), (y, self.times(to_y, logarithm))]
            }
            Binary::PowerConstant => {
                // x^c, c a number: c x^(c−1) dx; the exponent's share is not needed.
                let Instruction::Number(c) = self.instructions[y] else {
                    return None;
                };
                let exponent = self.emit(Instruction::Number(c - 1.0));
                let power = self.emit(Instruction::Binary(Binary::PowerConstant, x, exponent));
                let share = self.scaled(a, c);
                [(x, self.times(share, power)), (y, Adjoint::Zero)]
            }
            Binary::Atan2 => {
                // atan2(x, y) = the angle of (y, x): dx y/(x² + y²) − dy x/(x² + y²).
                let (xx, yy) = (
                    self.emit(Instruction::Square(x)),
                    self.emit(Instruction::Square(y)),
                );
                let radius = self.emit(Instruction::Binary(Binary::Add, xx, yy));
                let reciprocal = self.emit(Instruction::Reciprocal(radius));
                let share = self.times(a, reciprocal);
                let to_y = self.times(share, x);
                [(x, self.times(share, y)), (y, self.scaled(to_y, -1.0))]
            }
        })
    }
}

/// Where a slot's gradient comes from in a program: nothing, a number, or a number times a
/// register.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Output {
    Zero,
    Constant(f64),
    Register(f64, usize),
}

/// The value or the force ∂ℓ/∂q of one kind of term as a straight-line program on registers
/// of [`LANES`] sites (see the [module docs](self)).
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    /// (destination register, instruction on registers).
    steps: Vec<(usize, Instruction)>,
    /// ℓ (one output), or ∂ℓ/∂q of each slot.
    outputs: Vec<Output>,
    /// The number of registers the steps use (at most [`MAX_REGISTERS`]).
    registers: usize,
}

/// Where the lanes of a batch read their coordinates and write their forces: slot u of
/// lane l is entry `bases[u] + l · stride` of q, q̇ and the force.
#[derive(Debug, Clone, Copy)]
pub struct Lanes<'a> {
    /// The number of sites in the batch (at most [`LANES`]).
    pub count: usize,
    /// Each slot's entry at the first site.
    pub bases: &'a [usize],
    /// The distance between the entries of neighbouring sites.
    pub stride: usize,
}

impl Program {
    /// The program of `tape`'s value; `None` if it needs more than [`MAX_REGISTERS`]
    /// registers.
    pub fn value(tape: &Tape) -> Option<Program> {
        let mut builder = Builder::default();
        let output = builder.forward(tape)?;
        Program::compile(builder.instructions, &[Adjoint::Value(1.0, output)])
    }

    /// The program of `tape`'s force ∂ℓ/∂q in the coordinates of its `width` slots; `None`
    /// if it needs more than [`MAX_REGISTERS`] registers.
    pub fn force(tape: &Tape, width: usize) -> Option<Program> {
        let mut builder = Builder::default();
        let output = builder.forward(tape)?;
        let gradient = builder.reverse(output, width)?;
        Program::compile(builder.instructions, &gradient)
    }

    /// The program of the `instructions` that `outputs` need, on registers.
    fn compile(instructions: Vec<Instruction>, outputs: &[Adjoint]) -> Option<Program> {
        // The instructions the outputs need, each after its operands.
        let mut needed = vec![false; instructions.len()];
        for output in outputs {
            if let Adjoint::Value(_, x) = output {
                needed[*x] = true;
            }
        }
        for value in (0..instructions.len()).rev() {
            if needed[value] {
                for operand in instructions[value].operands().into_iter().flatten() {
                    needed[operand] = true;
                }
            }
        }
        let mut last_use = vec![0; instructions.len()];
        for (value, instruction) in instructions.iter().enumerate() {
            if needed[value] {
                for operand in instruction.operands().into_iter().flatten() {
                    last_use[operand] = value;
                }
            }
        }
        for output in outputs {
            if let Adjoint::Value(_, x) = output {
                last_use[*x] = usize::MAX;
            }
        }
        // Registers, reused once their value is dead (never as the destination of the
        // instruction that reads them last: operands and destination stay apart).
        let mut register = vec![usize::MAX; instructions.len()];
        let mut free: Vec<usize> = Vec::new();
        let mut count = 0;
        let mut steps = Vec::new();
        for (value, instruction) in instructions.iter().enumerate() {
            if !needed[value] {
                continue;
            }
            let destination = free.pop().unwrap_or_else(|| {
                count += 1;
                count - 1
            });
            register[value] = destination;
            steps.push((destination, instruction.renamed(|x| register[x])));
            for operand in instruction.operands().into_iter().flatten() {
                if last_use[operand] == value && !free.contains(&register[operand]) {
                    free.push(register[operand]);
                }
            }
        }
        if count > MAX_REGISTERS {
            return None;
        }
        let outputs = outputs
            .iter()
            .map(|output| match *output {
                Adjoint::Zero => Output::Zero,
                Adjoint::Constant(c) => Output::Constant(c),
                Adjoint::Value(c, x) => Output::Register(c, register[x]),
            })
            .collect();
        Some(Program {
            steps,
            outputs,
            registers: count,
        })
    }

    /// The number of registers the steps use (at most [`MAX_REGISTERS`]).
    pub fn register_count(&self) -> usize {
        self.registers
    }

    /// The sum of ℓ over the sites of `lanes` at time `t` (a [`Program::value`]), reading
    /// their coordinates and velocities from `q` and `v`, with `registers` as scratch.
    #[inline]
    pub fn sum(
        &self,
        registers: &mut Registers,
        lanes: Lanes<'_>,
        t: f64,
        q: &[f64],
        v: &[f64],
    ) -> f64 {
        self.execute(registers, lanes.loader(t, q, v));
        match self.outputs.first() {
            Some(&Output::Register(c, r)) => c * registers[r][..lanes.count].iter().sum::<f64>(),
            Some(Output::Constant(c)) => c * lanes.count as f64,
            Some(Output::Zero) | None => 0.0,
        }
    }

    /// Add the force ∂ℓ/∂q of the sites of `lanes` at time `t` (a [`Program::force`]) to
    /// `force`, reading their coordinates and velocities from `q` and `v`, with `registers`
    /// as scratch.
    #[inline]
    pub fn add_force(
        &self,
        registers: &mut Registers,
        lanes: Lanes<'_>,
        t: f64,
        q: &[f64],
        v: &[f64],
        force: &mut [f64],
    ) {
        self.execute(registers, lanes.loader(t, q, v));
        for (&output, &base) in self.outputs.iter().zip(lanes.bases) {
            let entries = force[base..]
                .iter_mut()
                .step_by(lanes.stride)
                .take(lanes.count);
            match output {
                Output::Zero => {}
                Output::Constant(c) => entries.for_each(|f| *f += c),
                Output::Register(c, r) => entries.zip(&registers[r]).for_each(|(f, g)| *f += c * g),
            }
        }
    }

    /// Run a [`Program::force`] on `W` points at once, one a lane: `load` fills the lanes of
    /// the time, a coordinate or a velocity; then `write(u, lane, ∂ℓ/∂q_u)` for every slot u
    /// and each of the first `count` lanes, with `registers` as scratch (at least
    /// [`Program::register_count`] of them).
    #[inline]
    pub fn forces<const W: usize>(
        &self,
        registers: &mut [[f64; W]],
        count: usize,
        load: impl FnMut(Source, &mut [f64; W]),
        mut write: impl FnMut(usize, usize, f64),
    ) {
        self.execute(registers, load);
        for (u, &output) in self.outputs.iter().enumerate() {
            match output {
                Output::Zero => (0..count).for_each(|lane| write(u, lane, 0.0)),
                Output::Constant(c) => (0..count).for_each(|lane| write(u, lane, c)),
                Output::Register(c, r) => registers[r][..count]
                    .iter()
                    .enumerate()
                    .for_each(|(lane, &g)| write(u, lane, c * g)),
            }
        }
    }

    /// Run the steps on `W` lanes, `load` filling the loads. Each step reads its operands
    /// out of the register file by value and writes its result back whole: the lanes run as
    /// vector instructions (a result written in place beside operands read in place would
    /// not: the compiler cannot tell them apart).
    #[inline]
    fn execute<const W: usize>(
        &self,
        registers: &mut [[f64; W]],
        mut load: impl FnMut(Source, &mut [f64; W]),
    ) {
        for &(destination, instruction) in &self.steps {
            let x = |x: usize| registers[x];
            let value = match instruction {
                Instruction::Number(c) => [c; W],
                Instruction::Time => {
                    load(Source::Time, &mut registers[destination]);
                    continue;
                }
                Instruction::Coordinate(u) => {
                    load(Source::Coordinate(u), &mut registers[destination]);
                    continue;
                }
                Instruction::Velocity(u) => {
                    load(Source::Velocity(u), &mut registers[destination]);
                    continue;
                }
                Instruction::Negate(a) => x(a).map(|x| -x),
                Instruction::Scale(a, c) => x(a).map(|x| x * c),
                Instruction::Shift(a, c) => x(a).map(|x| x + c),
                Instruction::DivideBy(a, c) => x(a).map(|x| x / c),
                Instruction::Reciprocal(a) => x(a).map(f64::recip),
                Instruction::Square(a) => x(a).map(|x| x * x),
                Instruction::PowerInteger(a, n) => power(x(a), n),
                // One lane loop per function, not a `match` in every lane: `sqrt` and
                // `abs` then run as vector instructions.
                Instruction::Call(function, a) => {
                    let a = x(a);
                    match function {
                        Function::Sqrt => a.map(f64::sqrt),
                        Function::Abs => a.map(|x| if x < 0.0 { -x } else { x }),
                        Function::Sin => a.map(f64::sin),
                        Function::Cos => a.map(f64::cos),
                        Function::Tan => a.map(f64::tan),
                        Function::Asin => a.map(f64::asin),
                        Function::Acos => a.map(f64::acos),
                        Function::Atan => a.map(f64::atan),
                        Function::Sinh => a.map(f64::sinh),
                        Function::Cosh => a.map(f64::cosh),
                        Function::Tanh => a.map(f64::tanh),
                        Function::Exp => a.map(f64::exp),
                        Function::Ln => a.map(f64::ln),
                    }
                }
                Instruction::Sign(a) => x(a).map(|x| if x < 0.0 { -1.0 } else { 1.0 }),
                Instruction::Binary(binary, a, b) => {
                    let (a, b) = (x(a), x(b));
                    match binary {
                        Binary::Add => zip(a, b, |x, y| x + y),
                        Binary::Subtract => zip(a, b, |x, y| x - y),
                        Binary::Multiply => zip(a, b, |x, y| x * y),
                        Binary::Divide => zip(a, b, |x, y| x / y),
                        other => zip(a, b, |x, y| other.apply(x, y)),
                    }
                }
            };
            registers[destination] = value;
        }
    }
}

/// What a load instruction reads, lane by lane.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Source {
    /// The time.
    Time,
    /// Coordinate (slot) u.
    Coordinate(usize),
    /// Velocity (slot) u.
    Velocity(usize),
}

impl Lanes<'_> {
    /// The loads of these lanes: slot u of lane l at entry `bases[u] + l · stride` of q or
    /// q̇, the same time on every lane.
    #[inline]
    fn loader<'a>(
        &'a self,
        t: f64,
        q: &'a [f64],
        v: &'a [f64],
    ) -> impl FnMut(Source, &mut [f64; LANES]) + 'a {
        let Lanes {
            count,
            bases,
            stride,
        } = *self;
        move |source, target| {
            let (from, base) = match source {
                Source::Time => return target.fill(t),
                Source::Coordinate(u) => (q, bases[u]),
                Source::Velocity(u) => (v, bases[u]),
            };
            if stride == 1 {
                target[..count].copy_from_slice(&from[base..base + count]);
            } else {
                for (lane, x) in target[..count].iter_mut().enumerate() {
                    *x = from[base + lane * stride];
                }
            }
        }
    }
}

/// f(x, y), lane by lane.
#[inline(always)]
fn zip<const W: usize>(x: [f64; W], y: [f64; W], f: impl Fn(f64, f64) -> f64) -> [f64; W] {
    std::array::from_fn(|lane| f(x[lane], y[lane]))
}

/// xⁿ lane by lane, by repeated squaring in the order of `f64::powi` (compiler-rt's
/// `__powidf2`: its digits), each squaring and product on all lanes at once rather than a
/// call per lane.
#[inline(always)]
fn power<const W: usize>(mut x: [f64; W], n: i32) -> [f64; W] {
    let mut result = [1.0; W];
    let mut bits = n.unsigned_abs();
    loop {
        if bits & 1 == 1 {
            result.iter_mut().zip(x).for_each(|(r, x)| *r *= x);
        }
        bits >>= 1;
        if bits == 0 {
            break;
        }
        x.iter_mut().for_each(|x| *x *= *x);
    }
    if n < 0 {
        result.iter_mut().for_each(|r| *r = 1.0 / *r);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::text::expression::{Expression, Velocities};
    use crate::model::text::tree::Names;

    /// The tape of `text` in the coordinates x, y with the parameters a, b = `values`.
    fn tape(text: &str, values: &[f64]) -> Tape {
        let names = Names {
            coordinates: &["x", "y"],
            velocities: &["vx", "vy"],
            parameters: &["a", "b"],
            phase_space: true,
            families: &[],
            size: None,
        };
        Expression::parse(text, "lagrangian", &names)
            .unwrap()
            .compile(values, Velocities::Read)
    }

    #[test]
    fn the_fput_spring_force_folds_to_its_polynomial() {
        let (alpha, beta) = (0.25, 0.5);
        let spring = tape("-(0.5*(y-x)^2 + a/3*(y-x)^3 + b/4*(y-x)^4)", &[alpha, beta]);
        let gradient = Program::force(&spring, 2).unwrap();
        // The loads, d = y − x, d², d³, −d − α d² − β d³ in four (the scalings folded into
        // the coefficients), and no negative: the force on x is the same register, negated
        // as it is written. Neither ℓ's value nor d⁴, and d computed once.
        assert_eq!(gradient.steps.len(), 9, "{:?}", gradient.steps);
        assert_eq!(gradient.outputs[0], Output::Register(-1.0, 0));
        assert_eq!(gradient.outputs[1], Output::Register(1.0, 0));
        // A chain of springs: lane l reads x = q[l], y = q[l + 1].
        let q: Vec<f64> = (0..6).map(|i| 0.3 * (1.7 * f64::from(i)).sin()).collect();
        let mut force = vec![0.0; 6];
        let mut registers = [[0.0; LANES]; MAX_REGISTERS];
        let lanes = Lanes {
            count: 5,
            bases: &[0, 1],
            stride: 1,
        };
        gradient.add_force(&mut registers, lanes, 0.0, &q, &[0.0; 6], &mut force);
        let derivative = |d: f64| d + alpha * d * d + beta * d * d * d;
        for (j, f) in force.iter().enumerate() {
            let right = if j < 5 {
                derivative(q[j + 1] - q[j])
            } else {
                0.0
            };
            let left = if j > 0 {
                derivative(q[j] - q[j - 1])
            } else {
                0.0
            };
            // The same polynomial evaluated in another order: equal to a few ulps.
            assert!((f - (right - left)).abs() <= 1e-15, "{j}: {f}");
        }
    }

    /// Kepler's force: the loads, x², y², r² = x² + y², r, 1/r, 1/r², 1/r³ and the two
    /// products with x and y — the scalings of the chain rule (−1 from 1/r, ½ from √, 2 from
    /// the squares) folded into one factor −1 applied as the force is written.
    #[test]
    fn the_kepler_force_is_eleven_instructions() {
        let gradient = Program::force(&tape("a/sqrt(x^2 + y^2)", &[1.0, 0.0]), 2).unwrap();
        assert_eq!(gradient.steps.len(), 11, "{:?}", gradient.steps);
        let mut registers = [[0.0; LANES]; MAX_REGISTERS];
        let lanes = Lanes {
            count: 1,
            bases: &[0, 1],
            stride: 1,
        };
        let (q, mut force) = ([0.6, -0.8], [0.0; 2]);
        gradient.add_force(&mut registers, lanes, 0.0, &q, &[0.0; 2], &mut force);
        // ∂(1/r)/∂q = −q/r³ at r = 1.
        assert!(
            (force[0] + 0.6).abs() <= 1e-15 && (force[1] - 0.8).abs() <= 1e-15,
            "{force:?}"
        );
    }

    /// Integer powers on all lanes at once have `f64::powi`'s digits, for every sign and size
    /// of the exponent.
    #[test]
    fn integer_powers_of_lanes_are_powi() {
        let x: [f64; 4] = [0.3, -1.7, 2.9e3, -4.1e-5];
        for n in [
            0,
            1,
            2,
            3,
            4,
            5,
            7,
            12,
            31,
            -1,
            -2,
            -3,
            -8,
            -13,
            i32::MAX,
            i32::MIN,
        ] {
            for (got, x) in power(x, n).iter().zip(x) {
                assert_eq!(got.to_bits(), x.powi(n).to_bits(), "{x}^{n}: {got}");
            }
        }
    }

    #[test]
    fn every_instruction_has_the_dual_numbers_derivative() {
        let text = "sin(x)*cos(y) + tan(0.1*x) - asin(0.2*y) + acos(0.1*x) + atan(y)/4 \
                    + sinh(x)*cosh(y)*tanh(x) + exp(y)*ln(2 + x^2) + sqrt(3 + y^2) \
                    + abs(x - y)^1.5 + (1 + x^2)^y + atan2(x, 2 + y) + 1/(2 + x^2) \
                    - (1 + y^2)^-2 + x^5 + x*y*a + b - x/3 + vx*x^2";
        let tape = tape(text, &[0.7, 1.9]);
        let gradient = Program::force(&tape, 2).unwrap();
        for (x, y) in [(0.3, -0.4), (-0.8, 0.6)] {
            let mut force = [0.0; 2];
            let mut registers = [[0.0; LANES]; MAX_REGISTERS];
            let lanes = Lanes {
                count: 1,
                bases: &[0, 1],
                stride: 1,
            };
            gradient.add_force(&mut registers, lanes, 0.0, &[x, y], &[0.5, 0.0], &mut force);
            let (_, dx) = num_dual::first_derivative(
                |x| tape.evaluate(0.0.into(), &[x, y.into()], &[0.5.into(), 0.0.into()]),
                x,
            );
            let (_, dy) = num_dual::first_derivative(
                |y| tape.evaluate(0.0.into(), &[x.into(), y], &[0.5.into(), 0.0.into()]),
                y,
            );
            assert!(
                (force[0] - dx).abs() <= 1e-14 * dx.abs().max(1.0),
                "{force:?} {dx}"
            );
            assert!(
                (force[1] - dy).abs() <= 1e-14 * dy.abs().max(1.0),
                "{force:?} {dy}"
            );
        }
    }
}
