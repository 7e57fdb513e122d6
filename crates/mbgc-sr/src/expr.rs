//! Expressions as nested trees: for simplification and printing. Evolution works on the flat
//! postfix form; a finished equation is converted here, simplified and converted back.

use super::node::Node;
use super::program::Program;

/// An expression as a nested tree, the form simplification rewrites and printing walks.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// Input variable `k`.
    Var(u16),
    /// A constant.
    Const(f64),
    /// A unary function (`Node::Neg`, `Node::Sqrt`, ...) applied to its argument.
    Unary(Node, Box<Expr>),
    /// A binary operator (`Node::Add`, `Sub`, `Mul`, `Div`) applied to (left, right).
    Binary(Node, Box<Expr>, Box<Expr>),
}

use Expr::{Binary, Const, Unary, Var};

fn bin(op: Node, a: Expr, b: Expr) -> Expr {
    Binary(op, Box::new(a), Box::new(b))
}

impl Expr {
    /// The tree of a well-formed postfix program; panics on a malformed or empty one.
    pub fn from_postfix(p: &[Node]) -> Expr {
        let mut stack: Vec<Expr> = Vec::with_capacity(p.len());
        for &n in p {
            let e = match n {
                Node::Var(k) => Var(k),
                Node::Const(c) => Const(c),
                f if f.arity() == 1 => Unary(f, Box::new(stack.pop().expect("postfix"))),
                f => {
                    let r = stack.pop().expect("postfix");
                    let l = stack.pop().expect("postfix");
                    bin(f, l, r)
                }
            };
            stack.push(e);
        }
        stack.pop().expect("non-empty program")
    }

    /// The postfix program of the tree (the inverse of [`Expr::from_postfix`]).
    pub fn to_postfix(&self) -> Program {
        let mut out = Vec::new();
        self.push_postfix(&mut out);
        out
    }

    fn push_postfix(&self, out: &mut Program) {
        match self {
            Var(k) => out.push(Node::Var(*k)),
            Const(c) => out.push(Node::Const(*c)),
            Unary(f, a) => {
                a.push_postfix(out);
                out.push(*f);
            }
            Binary(f, a, b) => {
                a.push_postfix(out);
                b.push_postfix(out);
                out.push(*f);
            }
        }
    }

    fn as_const(&self) -> Option<f64> {
        match self {
            Const(c) => Some(*c),
            _ => None,
        }
    }

    /// Algebraic simplification to a fixed point: constant folding, neutral and absorbing
    /// elements, `x - x`, `x / x`, constants gathered to the right of sums and products.
    /// Values change at most by round-off, which the caller verifies.
    pub fn simplify(self) -> Expr {
        let mut e = self;
        for _ in 0..20 {
            let next = e.clone().pass();
            if next == e {
                break;
            }
            e = next;
        }
        e
    }

    fn pass(self) -> Expr {
        match self {
            Var(_) | Const(_) => self,
            Unary(f, a) => {
                let a = a.pass();
                match (f, a) {
                    (_, Const(c)) if f.unary(c).is_finite() => Const(f.unary(c)),
                    (Node::Neg, Unary(Node::Neg, x)) => *x,
                    (Node::Neg, Binary(Node::Sub, x, y)) => Binary(Node::Sub, y, x),
                    (f, a) => Unary(f, Box::new(a)),
                }
            }
            Binary(op, a, b) => {
                let (a, b) = (a.pass(), b.pass());
                if let (Some(x), Some(y)) = (a.as_const(), b.as_const()) {
                    let v = op.binary(x, y);
                    if v.is_finite() {
                        return Const(v);
                    }
                }
                simplify_binary(op, a, b)
            }
        }
    }

    /// Number of nodes.
    pub fn size(&self) -> usize {
        match self {
            Var(_) | Const(_) => 1,
            Unary(_, a) => 1 + a.size(),
            Binary(_, a, b) => 1 + a.size() + b.size(),
        }
    }
}

fn simplify_binary(op: Node, a: Expr, b: Expr) -> Expr {
    let (ca, cb) = (a.as_const(), b.as_const());
    match op {
        Node::Add => match (a, b) {
            (x, _) if cb == Some(0.0) => x,
            (_, y) if ca == Some(0.0) => y,
            // Constants to the right, then merged: c1 + x -> x + c1, (x + c1) + c2 -> x + c.
            (Const(c), y) => bin(Node::Add, y, Const(c)),
            (Binary(Node::Add, x, c1), Const(c2)) if c1.as_const().is_some() => {
                bin(Node::Add, *x, Const(c1.as_const().unwrap() + c2))
            }
            (Binary(Node::Add, x, c1), y) if c1.as_const().is_some() => {
                bin(Node::Add, bin(Node::Add, *x, y), *c1)
            }
            (x, Unary(Node::Neg, y)) => bin(Node::Sub, x, *y),
            (x, y) => bin(Node::Add, x, y),
        },
        Node::Sub => match (a, b) {
            (x, _) if cb == Some(0.0) => x,
            (_, y) if ca == Some(0.0) => Unary(Node::Neg, Box::new(y)),
            (x, y) if x == y => Const(0.0),
            (x, Const(c)) => bin(Node::Add, x, Const(-c)),
            (x, Unary(Node::Neg, y)) => bin(Node::Add, x, *y),
            (x, y) => bin(Node::Sub, x, y),
        },
        Node::Mul => match (a, b) {
            (_, _) if ca == Some(0.0) || cb == Some(0.0) => Const(0.0),
            (x, _) if cb == Some(1.0) => x,
            (_, y) if ca == Some(1.0) => y,
            (x, _) if cb == Some(-1.0) => Unary(Node::Neg, Box::new(x)),
            (_, y) if ca == Some(-1.0) => Unary(Node::Neg, Box::new(y)),
            (Const(c), y) => bin(Node::Mul, y, Const(c)),
            (Binary(Node::Mul, x, c1), Const(c2)) if c1.as_const().is_some() => {
                bin(Node::Mul, *x, Const(c1.as_const().unwrap() * c2))
            }
            (Binary(Node::Mul, x, c1), y) if c1.as_const().is_some() => {
                bin(Node::Mul, bin(Node::Mul, *x, y), *c1)
            }
            (x, Binary(Node::Mul, y, c1)) if c1.as_const().is_some() => {
                bin(Node::Mul, bin(Node::Mul, x, *y), *c1)
            }
            (Unary(Node::Neg, x), y) => Unary(Node::Neg, Box::new(bin(Node::Mul, *x, y))),
            (x, Unary(Node::Neg, y)) => Unary(Node::Neg, Box::new(bin(Node::Mul, x, *y))),
            (x, y) => bin(Node::Mul, x, y),
        },
        Node::Div => match (a, b) {
            (x, _) if cb == Some(1.0) => x,
            (x, y) if x == y => Const(1.0),
            (_, _) if ca == Some(0.0) => Const(0.0),
            (x, Const(c)) if (1.0 / c).is_finite() => bin(Node::Mul, x, Const(1.0 / c)),
            (Binary(Node::Mul, x, c1), y) if c1.as_const().is_some() => {
                bin(Node::Mul, bin(Node::Div, *x, y), *c1)
            }
            (x, y) => bin(Node::Div, x, y),
        },
        _ => unreachable!("{op:?} is not binary"),
    }
}

/// How a C-like language writes what the tree means.
pub struct Syntax<'a> {
    /// Variable names, indexed by variable number.
    pub names: &'a [String],
    /// How a constant is written (e.g. [`exact_constant`], or rounded for display).
    pub constant: &'a dyn Fn(f64) -> String,
    /// A unary function applied to an already printed argument (not `Neg`).
    pub call: &'a dyn Fn(Node, &str) -> String,
    /// Square and cube as `a**2` (true) or through `call` (false).
    pub power_operator: bool,
}

/// Prints an expression in Python/sympy syntax with the given variable names and constant format.
pub fn infix(e: &Expr, names: &[String], constant: &dyn Fn(f64) -> String) -> String {
    infix_with(
        e,
        &Syntax {
            names,
            constant,
            call: &|f, a| format!("{}({a})", f.name()),
            power_operator: true,
        },
    )
}

/// Infix printing with minimal parentheses; the tree's grouping is kept exactly (left-associative
/// operators), so a language with IEEE arithmetic computes the same value as the evaluator.
pub fn infix_with(e: &Expr, syn: &Syntax) -> String {
    // Precedence: 1 sum, 2 product, 3 unary minus, 4 power, 5 atom/call.
    fn go(e: &Expr, syn: &Syntax) -> (String, u8) {
        match e {
            Var(k) => (syn.names[*k as usize].clone(), 5),
            Const(v) => {
                let s = (syn.constant)(*v);
                let p = if s.starts_with('-') { 3 } else { 5 };
                (s, p)
            }
            Unary(f, a) => {
                let (s, p) = go(a, syn);
                match f {
                    Node::Neg => (format!("-{}", wrap(s, p, 4)), 3),
                    Node::Square if syn.power_operator => (format!("{}**2", wrap(s, p, 5)), 4),
                    Node::Cube if syn.power_operator => (format!("{}**3", wrap(s, p, 5)), 4),
                    f => ((syn.call)(*f, &s), 5),
                }
            }
            Binary(f, a, b) => {
                let (sa, pa) = go(a, syn);
                let (sb, pb) = go(b, syn);
                match f {
                    // x + (-c) reads x - c (the same IEEE result).
                    Node::Add if matches!(**b, Const(v) if v < 0.0) => (
                        format!("{sa} - {}", (syn.constant)(-b.as_const().unwrap())),
                        1,
                    ),
                    Node::Add => (format!("{sa} + {}", wrap(sb, pb, 2)), 1),
                    Node::Sub => (format!("{sa} - {}", wrap(sb, pb, 2)), 1),
                    Node::Mul => (format!("{}*{}", wrap(sa, pa, 2), wrap(sb, pb, 3)), 2),
                    _ => (format!("{}/{}", wrap(sa, pa, 2), wrap(sb, pb, 4)), 2),
                }
            }
        }
    }
    fn wrap(s: String, p: u8, min: u8) -> String {
        if p < min {
            format!("({s})")
        } else {
            s
        }
    }
    go(e, syn).0
}

/// Shortest decimal that reads back as the same f64.
pub fn exact_constant(v: f64) -> String {
    format!("{v:?}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eval::{Dataset, Evaluator};

    fn names() -> Vec<String> {
        vec!["x".into(), "y".into()]
    }

    #[test]
    fn simplifies_neutral_elements_and_folds_constants() {
        // ((x * 1) + 0) * (2 * 3) - (y - y)
        let e = bin(
            Node::Sub,
            bin(
                Node::Mul,
                bin(Node::Add, bin(Node::Mul, Var(0), Const(1.0)), Const(0.0)),
                bin(Node::Mul, Const(2.0), Const(3.0)),
            ),
            bin(Node::Sub, Var(1), Var(1)),
        );
        let s = e.simplify();
        assert_eq!(s, bin(Node::Mul, Var(0), Const(6.0)));
        assert_eq!(infix(&s, &names(), &exact_constant), "x*6.0");
    }

    #[test]
    fn merges_scaling_constants() {
        // 2 + 3 * ((x / 4) * y)  ->  (x * y) * 0.75 + 2
        let e = bin(
            Node::Add,
            Const(2.0),
            bin(
                Node::Mul,
                Const(3.0),
                bin(Node::Mul, bin(Node::Div, Var(0), Const(4.0)), Var(1)),
            ),
        );
        let s = e.simplify();
        assert_eq!(infix(&s, &names(), &exact_constant), "x*y*0.75 + 2.0");
    }

    #[test]
    fn printing_keeps_precedence() {
        // (x - y) / (x * y)  and  -(x + y)**2 and x - (y - 1)
        let e = bin(
            Node::Div,
            bin(Node::Sub, Var(0), Var(1)),
            bin(Node::Mul, Var(0), Var(1)),
        );
        assert_eq!(infix(&e, &names(), &exact_constant), "(x - y)/(x*y)");
        let e = Unary(
            Node::Neg,
            Box::new(Unary(
                Node::Square,
                Box::new(bin(Node::Add, Var(0), Var(1))),
            )),
        );
        assert_eq!(infix(&e, &names(), &exact_constant), "-(x + y)**2");
        let e = bin(Node::Sub, Var(0), bin(Node::Sub, Var(1), Const(1.0)));
        assert_eq!(infix(&e, &names(), &exact_constant), "x - (y - 1.0)");
    }

    #[test]
    fn simplification_keeps_values() {
        let x: Vec<f64> = (0..50).map(|i| 0.3 + i as f64 * 0.1).collect();
        let y: Vec<f64> = x.iter().map(|v| v * 0.7 + 0.2).collect();
        let d = Dataset::new(vec![x, y], vec![0.0; 50]);
        // exp(-(x*2)) / ((y + 1) - 1) - 3 * (x / 0.5) + sqrt(x - -1)
        let e = bin(
            Node::Add,
            bin(
                Node::Sub,
                bin(
                    Node::Div,
                    Unary(
                        Node::Exp,
                        Box::new(Unary(
                            Node::Neg,
                            Box::new(bin(Node::Mul, Var(0), Const(2.0))),
                        )),
                    ),
                    bin(Node::Sub, bin(Node::Add, Var(1), Const(1.0)), Const(1.0)),
                ),
                bin(Node::Mul, Const(3.0), bin(Node::Div, Var(0), Const(0.5))),
            ),
            Unary(Node::Sqrt, Box::new(bin(Node::Sub, Var(0), Const(-1.0)))),
        );
        let s = e.clone().simplify();
        assert!(s.size() < e.size());
        let mut ev = Evaluator::new();
        let (mut a, mut b) = (vec![0.0; 50], vec![0.0; 50]);
        assert!(ev.eval(&e.to_postfix(), &d.x, &mut a));
        assert!(ev.eval(&s.to_postfix(), &d.x, &mut b));
        for (a, b) in a.iter().zip(&b) {
            assert!((a - b).abs() <= 1e-13 * a.abs().max(1.0));
        }
    }
}
