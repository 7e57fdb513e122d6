//! The alphabet of expression trees: variables, constants and the function set.

use serde::{Deserialize, Serialize};

/// One node of a postfix expression. Functions take their arguments from the nodes before them.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Node {
    /// Input column `k` (after the model's input transform).
    Var(u16),
    /// A constant, finite; tuned by [`crate::constants::Tuner`].
    Const(f64),
    /// a + b.
    Add,
    /// a - b (the earlier argument minus the later).
    Sub,
    /// a b.
    Mul,
    /// a / b, unprotected (gplearn returns 1 when |b| <= 0.001; here a zero divisor makes the
    /// tree invalid).
    Div,
    /// -a.
    Neg,
    /// a^2.
    Square,
    /// a^3.
    Cube,
    /// sqrt(a), defined for a >= 0 (gplearn takes sqrt(|a|)).
    Sqrt,
    /// Natural logarithm ln(a), defined for a > 0 (gplearn takes ln|a|, and 0 near 0).
    Log,
    /// e^a; overflows to infinity above a = 709.78, which invalidates the tree.
    Exp,
    /// tanh(a), bounded in (-1, 1): a smooth saturation.
    Tanh,
    /// sin(a), a in radians.
    Sin,
    /// cos(a), a in radians.
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
    /// Number of arguments: 0 for terminals, 2 for + - * /, 1 for the other functions.
    pub fn arity(self) -> usize {
        match self {
            Node::Var(_) | Node::Const(_) => 0,
            Node::Add | Node::Sub | Node::Mul | Node::Div => 2,
            _ => 1,
        }
    }

    /// Whether the node is a leaf (a variable or a constant).
    pub fn is_terminal(self) -> bool {
        self.arity() == 0
    }

    /// Its name in [`FUNCTIONS`] (`div`, `tanh`), or `var` / `const` for terminals; also the
    /// function name printed by [`crate::expr::infix`].
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

    /// The function called `name` in [`FUNCTIONS`], if any.
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

    /// Applies a binary function to (a, b); real maths, no protection (a / 0 is infinite or NaN).
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

/// Parses a comma-separated function set such as `add,sub,mul,div,sqrt,log,exp,tanh`; repeated
/// names count once; an unknown name or an empty set is an error that lists the known names.
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
