//! The alphabet of expression trees: variables, constants and the function set.

use serde::{Deserialize, Serialize};

/// One node of a postfix expression. Functions take their arguments from the nodes before them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Node {
    /// Input column `k` (after the model's input transform).
    Var(u16),
    Const(f64),
    Add,
    Sub,
    Mul,
    Div,
    Neg,
    Square,
    Cube,
    Sqrt,
    Log,
    Exp,
    Tanh,
    Sin,
    Cos,
}

/// Functions a user can put in the function set, by the names used on the command line.
pub const FUNCTIONS: &[(&str, Node)] = &[
    ("add", Node::Add),
    ("sub", Node::Sub),
    ("mul", Node::Mul),
    ("div", Node::Div),
    ("neg", Node::Neg),
    ("square", Node::Square),
    ("cube", Node::Cube),
    ("sqrt", Node::Sqrt),
    ("log", Node::Log),
    ("exp", Node::Exp),
    ("tanh", Node::Tanh),
    ("sin", Node::Sin),
    ("cos", Node::Cos),
];

/// Seed 004's function set: + - * / sqrt log exp tanh.
pub const SEED004_FUNCTIONS: &str = "add,sub,mul,div,sqrt,log,exp,tanh";

impl Node {
    pub fn arity(self) -> usize {
        match self {
            Node::Var(_) | Node::Const(_) => 0,
            Node::Add | Node::Sub | Node::Mul | Node::Div => 2,
            _ => 1,
        }
    }

    pub fn is_terminal(self) -> bool {
        self.arity() == 0
    }

    pub fn name(self) -> &'static str {
        match self {
            Node::Var(_) => "var",
            Node::Const(_) => "const",
            _ => FUNCTIONS
                .iter()
                .find(|(_, n)| *n == self)
                .map(|(s, _)| *s)
                .unwrap_or("?"),
        }
    }

    pub fn from_name(name: &str) -> Option<Node> {
        FUNCTIONS.iter().find(|(s, _)| *s == name).map(|&(_, n)| n)
    }

    /// Applies a unary function; real maths, no protection: invalid domains give NaN or inf.
    #[inline(always)]
    pub fn unary(self, a: f64) -> f64 {
        match self {
            Node::Neg => -a,
            Node::Square => a * a,
            Node::Cube => a * a * a,
            Node::Sqrt => a.sqrt(),
            Node::Log => a.ln(),
            Node::Exp => a.exp(),
            Node::Tanh => a.tanh(),
            Node::Sin => a.sin(),
            Node::Cos => a.cos(),
            _ => unreachable!("{self:?} is not unary"),
        }
    }

    #[inline(always)]
    pub fn binary(self, a: f64, b: f64) -> f64 {
        match self {
            Node::Add => a + b,
            Node::Sub => a - b,
            Node::Mul => a * b,
            Node::Div => a / b,
            _ => unreachable!("{self:?} is not binary"),
        }
    }
}

/// Parses a comma-separated function set such as `add,sub,mul,div,sqrt,log,exp,tanh`.
pub fn parse_function_set(list: &str) -> Result<Vec<Node>, String> {
    let mut set = Vec::new();
    for name in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let node = Node::from_name(name).ok_or_else(|| {
            let known: Vec<&str> = FUNCTIONS.iter().map(|(s, _)| *s).collect();
            format!("unknown function '{name}' (known: {})", known.join(", "))
        })?;
        if !set.contains(&node) {
            set.push(node);
        }
    }
    if set.is_empty() {
        return Err("the function set is empty".into());
    }
    Ok(set)
}
