//! Profile expressions compiled to a typed tree of f64 operations, evaluated without
//! allocation: the per-point form of an expression sampled at every cell centre (10⁶
//! evaluations for a 1000 × 1000 raster).
//!
//! The tree is built once from `evalexpr`'s operator tree (after its integer literals
//! became floats) and gives the same value as `evalexpr`'s evaluation through the
//! profile context, bit for bit: the same f64 operation per node (`+ − × ÷ %`, `^` as
//! `powf`, the comparisons, `&& || !`), the same functions, every argument evaluated
//! (the branches of `if` too, as `evalexpr` does, so that an error in either branch is
//! an error). Each node has a static type, number or truth value; an expression that
//! does not type-check this way (strings, tuples outside a call, `;` chains, a wrong
//! number of arguments, a truth value as result) is not compiled, and is evaluated by
//! `evalexpr` as before, with its messages.

use evalexpr::{DefaultNumericTypes, Node, Operator, Value};

/// A compiled number-valued expression.
#[derive(Debug, Clone)]
pub(crate) struct Compiled {
    root: Num,
}

#[derive(Debug, Clone, Copy)]
enum Var {
    X,
    Y,
    B,
}

#[derive(Debug, Clone, Copy)]
enum Binary {
    Add,
    Sub,
    Mul,
    Div,
    Mod,
    Pow,
    Atan2,
    Noise,
}

#[derive(Debug, Clone, Copy)]
enum Fold {
    Min,
    Max,
}

/// A number-valued node.
#[derive(Debug, Clone)]
enum Num {
    Const(f64),
    Var(Var),
    Neg(Box<Num>),
    Unary(fn(f64) -> f64, Box<Num>),
    Binary(Binary, Box<Num>, Box<Num>),
    Fold(Fold, Vec<Num>),
    If(Box<Truth>, Box<Num>, Box<Num>),
}

#[derive(Debug, Clone, Copy)]
enum Compare {
    Lt,
    Gt,
    Leq,
    Geq,
    Eq,
    Neq,
}

/// A node with a truth value.
#[derive(Debug, Clone)]
enum Truth {
    Const(bool),
    Compare(Compare, Box<Num>, Box<Num>),
    Same(bool, Box<Truth>, Box<Truth>),
    And(Box<Truth>, Box<Truth>),
    Or(Box<Truth>, Box<Truth>),
    Not(Box<Truth>),
}

type Tree = Node<DefaultNumericTypes>;

impl Compiled {
    /// The compiled form of `node` (the root of a parsed expression whose variables
    /// and functions were checked), or `None` where it does not type-check as a number.
    pub(crate) fn new(node: &Tree, allow_b: bool) -> Option<Compiled> {
        let b = Builder { allow_b };
        Some(Compiled { root: b.num(node)? })
    }

    /// The value at (x, y) over the bed elevation `b`; `Err` with the message of the
    /// failing function (`noise` with a seed that is no integer).
    pub(crate) fn eval(&self, x: f64, y: f64, b: f64) -> Result<f64, String> {
        num(&self.root, [x, y, b])
    }
}

struct Builder {
    allow_b: bool,
}

impl Builder {
    fn only_child<'a>(&self, node: &'a Tree) -> Option<&'a Tree> {
        match node.children() {
            [child] => Some(child),
            _ => None,
        }
    }

    fn two<'a>(&self, node: &'a Tree) -> Option<(&'a Tree, &'a Tree)> {
        match node.children() {
            [a, b] => Some((a, b)),
            _ => None,
        }
    }

    fn num(&self, node: &Tree) -> Option<Num> {
        let node = self.inner(node);
        let pair = |op: Binary| {
            let (a, b) = self.two(node)?;
            Some(Num::Binary(
                op,
                Box::new(self.num(a)?),
                Box::new(self.num(b)?),
            ))
        };
        match node.operator() {
            Operator::Const {
                value: Value::Float(v),
            } => Some(Num::Const(*v)),
            Operator::Const {
                value: Value::Int(i),
            } => Some(Num::Const(*i as f64)),
            Operator::VariableIdentifierRead { identifier } => match identifier.as_str() {
                "x" => Some(Num::Var(Var::X)),
                "y" => Some(Num::Var(Var::Y)),
                "b" if self.allow_b => Some(Num::Var(Var::B)),
                "pi" => Some(Num::Const(std::f64::consts::PI)),
                "deg" => Some(Num::Const(std::f64::consts::PI / 180.0)),
                _ => None,
            },
            Operator::Neg => Some(Num::Neg(Box::new(self.num(self.only_child(node)?)?))),
            Operator::Add => pair(Binary::Add),
            Operator::Sub => pair(Binary::Sub),
            Operator::Mul => pair(Binary::Mul),
            Operator::Div => pair(Binary::Div),
            Operator::Mod => pair(Binary::Mod),
            Operator::Exp => pair(Binary::Pow),
            Operator::FunctionIdentifier { identifier } => {
                self.call(identifier, self.only_child(node)?)
            }
            _ => None,
        }
    }

    /// The node inside parentheses: a root node (what `evalexpr` makes of a pair of
    /// parentheses) with one child has that child's value.
    fn inner<'a>(&self, mut node: &'a Tree) -> &'a Tree {
        while let (Operator::RootNode, [child]) = (node.operator(), node.children()) {
            node = child;
        }
        node
    }

    /// The arguments of a call: the children of a tuple, or the one argument.
    fn arguments<'a>(&self, argument: &'a Tree) -> &'a [Tree] {
        let argument = self.inner(argument);
        match argument.operator() {
            Operator::Tuple => argument.children(),
            _ => std::slice::from_ref(argument),
        }
    }

    fn call(&self, name: &str, argument: &Tree) -> Option<Num> {
        let args = self.arguments(argument);
        let unary = |f: fn(f64) -> f64| match args {
            [a] => Some(Num::Unary(f, Box::new(self.num(a)?))),
            _ => None,
        };
        let binary = |op: Binary| match args {
            [a, b] => Some(Num::Binary(
                op,
                Box::new(self.num(a)?),
                Box::new(self.num(b)?),
            )),
            _ => None,
        };
        if let Some(f) = super::profile::unary_function(name) {
            return unary(f);
        }
        match name {
            "pow" => binary(Binary::Pow),
            "atan2" => binary(Binary::Atan2),
            "noise" => binary(Binary::Noise),
            "min" | "max" if !args.is_empty() => {
                let fold = if name == "min" { Fold::Min } else { Fold::Max };
                let items = args.iter().map(|a| self.num(a)).collect::<Option<_>>()?;
                Some(Num::Fold(fold, items))
            }
            "if" => match args {
                [c, a, b] => Some(Num::If(
                    Box::new(self.truth(c)?),
                    Box::new(self.num(a)?),
                    Box::new(self.num(b)?),
                )),
                _ => None,
            },
            _ => None,
        }
    }

    fn truth(&self, node: &Tree) -> Option<Truth> {
        let node = self.inner(node);
        let compare = |op: Compare| {
            let (a, b) = self.two(node)?;
            Some(Truth::Compare(
                op,
                Box::new(self.num(a)?),
                Box::new(self.num(b)?),
            ))
        };
        let both = |node: &Tree| {
            let (a, b) = self.two(node)?;
            Some((Box::new(self.truth(a)?), Box::new(self.truth(b)?)))
        };
        match node.operator() {
            Operator::Const {
                value: Value::Boolean(v),
            } => Some(Truth::Const(*v)),
            Operator::Lt => compare(Compare::Lt),
            Operator::Gt => compare(Compare::Gt),
            Operator::Leq => compare(Compare::Leq),
            Operator::Geq => compare(Compare::Geq),
            // Equality of numbers, or else of truth values.
            Operator::Eq | Operator::Neq => {
                let equal = matches!(node.operator(), Operator::Eq);
                let op = if equal { Compare::Eq } else { Compare::Neq };
                compare(op).or_else(|| {
                    let (a, b) = both(node)?;
                    Some(Truth::Same(equal, a, b))
                })
            }
            Operator::And => both(node).map(|(a, b)| Truth::And(a, b)),
            Operator::Or => both(node).map(|(a, b)| Truth::Or(a, b)),
            Operator::Not => Some(Truth::Not(Box::new(self.truth(self.only_child(node)?)?))),
            _ => None,
        }
    }
}

fn num(node: &Num, at: [f64; 3]) -> Result<f64, String> {
    Ok(match node {
        Num::Const(v) => *v,
        Num::Var(v) => at[*v as usize],
        Num::Neg(a) => -num(a, at)?,
        Num::Unary(f, a) => f(num(a, at)?),
        Num::Binary(op, a, b) => {
            let (a, b) = (num(a, at)?, num(b, at)?);
            match op {
                Binary::Add => a + b,
                Binary::Sub => a - b,
                Binary::Mul => a * b,
                Binary::Div => a / b,
                Binary::Mod => a % b,
                Binary::Pow => a.powf(b),
                Binary::Atan2 => a.atan2(b),
                Binary::Noise => {
                    if !b.is_finite() || b.fract() != 0.0 {
                        return Err(format!("noise: the seed must be an integer, got {b}"));
                    }
                    super::profile::noise(a, b as i64)
                }
            }
        }
        Num::Fold(fold, items) => {
            let mut acc = num(&items[0], at)?;
            for item in &items[1..] {
                let v = num(item, at)?;
                acc = match fold {
                    Fold::Min => acc.min(v),
                    Fold::Max => acc.max(v),
                };
            }
            acc
        }
        Num::If(c, a, b) => {
            let (c, a, b) = (truth(c, at)?, num(a, at)?, num(b, at)?);
            if c {
                a
            } else {
                b
            }
        }
    })
}

fn truth(node: &Truth, at: [f64; 3]) -> Result<bool, String> {
    Ok(match node {
        Truth::Const(v) => *v,
        Truth::Compare(op, a, b) => {
            let (a, b) = (num(a, at)?, num(b, at)?);
            match op {
                Compare::Lt => a < b,
                Compare::Gt => a > b,
                Compare::Leq => a <= b,
                Compare::Geq => a >= b,
                Compare::Eq => a == b,
                Compare::Neq => a != b,
            }
        }
        Truth::Same(equal, a, b) => (truth(a, at)? == truth(b, at)?) == *equal,
        Truth::And(a, b) => {
            let (a, b) = (truth(a, at)?, truth(b, at)?);
            a && b
        }
        Truth::Or(a, b) => {
            let (a, b) = (truth(a, at)?, truth(b, at)?);
            a || b
        }
        Truth::Not(a) => !truth(a, at)?,
    })
}
