//! Value and gradient of a program with respect to its variables at one point (reverse mode),
//! for calibration: the metamodel's equations are differentiated exactly, not by differences.

use super::constants::children;
use super::node::Node;

/// `(f(x), df/dx)`, or `None` where a node is not finite (outside the equation's domain). `x`
/// holds one value per variable; the gradient is exact up to round-off (reverse mode, one
/// backward sweep), so a calibration's optimiser sees the metamodel's true slope.
///
/// ```
/// use mbgc_sr::grad::value_and_gradient;
/// use mbgc_sr::Node::{Add, Log, Square, Var};
///
/// // f = x0^2 + ln(x1): at (3, 2), f = 9 + ln 2 and grad f = (2 x0, 1 / x1) = (6, 0.5).
/// let f = [Var(0), Square, Var(1), Log, Add];
/// let (v, g) = value_and_gradient(&f, &[3.0, 2.0]).unwrap();
/// assert!((v - (9.0 + 2f64.ln())).abs() < 1e-15);
/// assert_eq!(g, vec![6.0, 0.5]);
/// // ln is undefined at x1 = -1: no value, rather than a protected stand-in.
/// assert!(value_and_gradient(&f, &[3.0, -1.0]).is_none());
/// ```
pub fn value_and_gradient(p: &[Node], x: &[f64]) -> Option<(f64, Vec<f64>)> {
    let ch = children(p);
    let mut v = vec![0.0; p.len()];
    for (i, &n) in p.iter().enumerate() {
        let (l, r) = ch[i];
        v[i] = match n {
            Node::Var(k) => x[k as usize],
            Node::Const(c) => c,
            f if f.arity() == 2 => f.binary(v[l], v[r]),
            f => f.unary(v[l]),
        };
        if !v[i].is_finite() {
            return None;
        }
    }
    let mut adj = vec![0.0; p.len()];
    let mut grad = vec![0.0; x.len()];
    let root = p.len() - 1;
    adj[root] = 1.0;
    for i in (0..p.len()).rev() {
        let (l, r) = ch[i];
        let g = adj[i];
        match p[i] {
            Node::Var(k) => grad[k as usize] += g,
            Node::Const(_) => {}
            Node::Add => {
                adj[l] = g;
                adj[r] = g;
            }
            Node::Sub => {
                adj[l] = g;
                adj[r] = -g;
            }
            Node::Mul => {
                adj[l] = g * v[r];
                adj[r] = g * v[l];
            }
            Node::Div => {
                adj[l] = g / v[r];
                adj[r] = -g * v[i] / v[r];
            }
            Node::Neg => adj[l] = -g,
            Node::Square => adj[l] = 2.0 * g * v[l],
            Node::Cube => adj[l] = 3.0 * g * v[l] * v[l],
            Node::Sqrt => adj[l] = 0.5 * g / v[i],
            Node::Log => adj[l] = g / v[l],
            Node::Exp => adj[l] = g * v[i],
            Node::Tanh => adj[l] = g * (1.0 - v[i] * v[i]),
            Node::Sin => adj[l] = g * v[l].cos(),
            Node::Cos => adj[l] = -g * v[l].sin(),
        }
    }
    grad.iter()
        .all(|g| g.is_finite())
        .then_some((v[root], grad))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn matches_finite_differences() {
        // x0 * exp(-x1) / sqrt(x0 + x2) + tanh(x1 * x2) - log(x0)^2
        let p = vec![
            Node::Var(0),
            Node::Var(1),
            Node::Neg,
            Node::Exp,
            Node::Mul,
            Node::Var(0),
            Node::Var(2),
            Node::Add,
            Node::Sqrt,
            Node::Div,
            Node::Var(1),
            Node::Var(2),
            Node::Mul,
            Node::Tanh,
            Node::Add,
            Node::Var(0),
            Node::Log,
            Node::Square,
            Node::Sub,
        ];
        let x = [1.7, 0.4, 0.9];
        let (f, g) = value_and_gradient(&p, &x).unwrap();
        let eval = |x: &[f64]| value_and_gradient(&p, x).unwrap().0;
        assert_eq!(f, eval(&x));
        for k in 0..3 {
            let h = 1e-6;
            let (mut a, mut b) = (x, x);
            a[k] += h;
            b[k] -= h;
            let fd = (eval(&a) - eval(&b)) / (2.0 * h);
            assert!((fd - g[k]).abs() < 1e-7, "{k}: {fd} vs {}", g[k]);
        }
        // log of a negative: outside the domain.
        assert!(value_and_gradient(&p, &[-1.0, 0.4, 3.0]).is_none());
    }
}
