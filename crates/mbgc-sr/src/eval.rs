//! Batched evaluation of postfix programs and their fitness.
//!
//! Rows are evaluated in batches of [`BATCH`] on a stack of fixed-size buffers, so one node costs
//! one tight loop over the batch and nothing is allocated per node. Every node's result is checked:
//! a non-finite value anywhere (log of a negative, division by zero, overflow) makes the program
//! invalid rather than being patched, so an equation means exactly what its export says.

use super::node::Node;

/// Rows per evaluation batch. A node's buffer is then 512 bytes, so the stack of a tree of the
/// default maximum length (64 nodes) is 32 KiB, about one L1 data cache, while each node's loop
/// is still long enough to vectorise.
pub const BATCH: usize = 64;

/// Column-major inputs (`x[var][row]`) and the target.
#[derive(Clone, Debug)]
pub struct Dataset {
    /// Input columns, one per variable, each with one value per row.
    pub x: Vec<Vec<f64>>,
    /// Target, one value per row.
    pub y: Vec<f64>,
    y_mean: f64,
    y_var: f64,
}

impl Dataset {
    /// A dataset of input columns `x` and target `y`; caches the target's mean and (population)
    /// variance. Panics if a column's length differs from the target's.
    pub fn new(x: Vec<Vec<f64>>, y: Vec<f64>) -> Dataset {
        assert!(x.iter().all(|c| c.len() == y.len()));
        let n = y.len().max(1) as f64;
        let y_mean = y.iter().sum::<f64>() / n;
        let y_var = y.iter().map(|v| (v - y_mean).powi(2)).sum::<f64>() / n;
        Dataset {
            x,
            y,
            y_mean,
            y_var,
        }
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.y.len()
    }

    /// Number of input variables.
    pub fn n_vars(&self) -> usize {
        self.x.len()
    }

    /// Mean of the target.
    pub fn y_mean(&self) -> f64 {
        self.y_mean
    }

    /// Variance of the target (divided by n): the denominator of every normalised error, so
    /// that 1 - nmse is R^2.
    pub fn y_var(&self) -> f64 {
        self.y_var
    }

    /// The rows at `idx`, in that order.
    pub fn subset(&self, idx: &[usize]) -> Dataset {
        Dataset::new(
            self.x
                .iter()
                .map(|c| idx.iter().map(|&i| c[i]).collect())
                .collect(),
            idx.iter().map(|&i| self.y[i]).collect(),
        )
    }
}

#[inline(always)]
pub(crate) fn all_finite(a: &[f64]) -> bool {
    const EXP: u64 = 0x7ff0_0000_0000_0000;
    // Integer OR-reduction vectorises; `all` with early exit does not.
    let mut bad = 0u64;
    for v in a {
        bad |= ((!v.to_bits() & EXP) == 0) as u64;
    }
    bad == 0
}

/// Per-thread scratch space for evaluation.
#[derive(Default)]
pub struct Evaluator {
    stack: Vec<[f64; BATCH]>,
    /// Nodes times rows evaluated so far (for speed reports).
    pub node_evals: u64,
}

impl Evaluator {
    /// Empty scratch space, grown on first use.
    pub fn new() -> Evaluator {
        Evaluator::default()
    }

    /// Evaluates `p` on every row into `out`; `false` if any intermediate value is not finite.
    pub fn eval(&mut self, p: &[Node], x: &[Vec<f64>], out: &mut [f64]) -> bool {
        if self.stack.len() < p.len() {
            self.stack.resize(p.len(), [0.0; BATCH]);
        }
        let n = out.len();
        self.node_evals += (p.len() * n) as u64;
        let mut r0 = 0;
        while r0 < n {
            let m = BATCH.min(n - r0);
            if !self.eval_batch(p, x, r0, m) {
                return false;
            }
            out[r0..r0 + m].copy_from_slice(&self.stack[0][..m]);
            r0 += m;
        }
        true
    }

    fn eval_batch(&mut self, p: &[Node], x: &[Vec<f64>], r0: usize, m: usize) -> bool {
        let stack = &mut self.stack;
        let mut sp = 0usize;
        for &node in p {
            match node {
                Node::Var(k) => {
                    stack[sp][..m].copy_from_slice(&x[k as usize][r0..r0 + m]);
                    sp += 1;
                }
                Node::Const(c) => {
                    stack[sp][..m].fill(c);
                    sp += 1;
                }
                Node::Add | Node::Sub | Node::Mul | Node::Div => {
                    sp -= 1;
                    let (lo, hi) = stack.split_at_mut(sp);
                    let a = &mut lo[sp - 1][..m];
                    let b = &hi[0][..m];
                    match node {
                        Node::Add => a.iter_mut().zip(b).for_each(|(a, b)| *a += b),
                        Node::Sub => a.iter_mut().zip(b).for_each(|(a, b)| *a -= b),
                        Node::Mul => a.iter_mut().zip(b).for_each(|(a, b)| *a *= b),
                        _ => a.iter_mut().zip(b).for_each(|(a, b)| *a /= b),
                    }
                    if !all_finite(a) {
                        return false;
                    }
                }
                f => {
                    let a = &mut stack[sp - 1][..m];
                    match f {
                        Node::Neg => a.iter_mut().for_each(|v| *v = -*v),
                        Node::Square => a.iter_mut().for_each(|v| *v *= *v),
                        Node::Cube => a.iter_mut().for_each(|v| *v = *v * *v * *v),
                        Node::Sqrt => a.iter_mut().for_each(|v| *v = v.sqrt()),
                        Node::Log => a.iter_mut().for_each(|v| *v = v.ln()),
                        Node::Exp => a.iter_mut().for_each(|v| *v = v.exp()),
                        Node::Tanh => a.iter_mut().for_each(|v| *v = v.tanh()),
                        Node::Sin => a.iter_mut().for_each(|v| *v = v.sin()),
                        _ => a.iter_mut().for_each(|v| *v = v.cos()),
                    }
                    if !all_finite(a) {
                        return false;
                    }
                }
            }
        }
        debug_assert_eq!(sp, 1);
        true
    }
}

/// How well a program's output explains the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Score {
    /// Mean squared error over the target's variance (= 1 - R^2); `INFINITY` when invalid.
    pub nmse: f64,
    /// Output = `intercept + slope * program` (slope 1, intercept 0 without linear scaling).
    pub intercept: f64,
    /// The slope of that map (0 when the program's output is constant).
    pub slope: f64,
}

impl Score {
    /// The score of a program that is not finite on some row: infinite error, identity map.
    pub const INVALID: Score = Score {
        nmse: f64::INFINITY,
        intercept: 0.0,
        slope: 1.0,
    };

    /// Whether the error is finite.
    pub fn is_valid(&self) -> bool {
        self.nmse.is_finite()
    }
}

/// Scores raw program outputs; with `linear_scaling` the best affine map of the output is used
/// (Keijzer 2003), which frees the search from finding offsets and scales.
pub fn score(pred: &[f64], data: &Dataset, linear_scaling: bool) -> Score {
    let n = pred.len() as f64;
    let y = &data.y;
    let var_y = data.y_var().max(f64::MIN_POSITIVE);
    let (intercept, slope) = if linear_scaling {
        let mp = pred.iter().sum::<f64>() / n;
        let (mut vp, mut cov) = (0.0, 0.0);
        for (p, y) in pred.iter().zip(y) {
            let d = p - mp;
            vp += d * d;
            cov += d * (y - data.y_mean());
        }
        // An output that varies only by round-off is a constant: scaling it up would fit noise.
        let floor = 1e-12 * mp.abs().max(1e-300);
        if vp / n <= floor * floor {
            (data.y_mean(), 0.0)
        } else {
            let b = cov / vp;
            (data.y_mean() - b * mp, b)
        }
    } else {
        (0.0, 1.0)
    };
    let sse: f64 = pred
        .iter()
        .zip(y)
        .map(|(p, y)| (y - intercept - slope * p).powi(2))
        .sum();
    let nmse = sse / (n * var_y);
    if !nmse.is_finite() {
        return Score::INVALID;
    }
    Score {
        nmse,
        intercept,
        slope,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn data() -> Dataset {
        let x0: Vec<f64> = (0..150).map(|i| 0.5 + i as f64 * 0.03).collect();
        let x1: Vec<f64> = (0..150).map(|i| 2.0 - i as f64 * 0.01).collect();
        let y = x0.iter().zip(&x1).map(|(a, b)| a * b + 1.0).collect();
        Dataset::new(vec![x0, x1], y)
    }

    #[test]
    fn evaluates_across_batches_like_scalar_code() {
        let d = data();
        // sqrt(x0) * exp(x1) - x0 / x1
        let p = vec![
            Node::Var(0),
            Node::Sqrt,
            Node::Var(1),
            Node::Exp,
            Node::Mul,
            Node::Var(0),
            Node::Var(1),
            Node::Div,
            Node::Sub,
        ];
        let mut out = vec![0.0; d.rows()];
        let mut ev = Evaluator::new();
        assert!(ev.eval(&p, &d.x, &mut out));
        for (i, o) in out.iter().enumerate() {
            let (a, b) = (d.x[0][i], d.x[1][i]);
            assert_eq!(*o, a.sqrt() * b.exp() - a / b);
        }
        assert_eq!(ev.node_evals, 9 * 150);
    }

    #[test]
    fn invalid_domains_make_a_program_invalid() {
        let d = data();
        let mut out = vec![0.0; d.rows()];
        let mut ev = Evaluator::new();
        // log(x1 - 1.5) is negative for part of the rows.
        let p = vec![Node::Var(1), Node::Const(1.5), Node::Sub, Node::Log];
        assert!(!ev.eval(&p, &d.x, &mut out));
        // tanh(1 / (x0 - x0)) would be "fine" after tanh, but the division is not.
        let p = vec![
            Node::Const(1.0),
            Node::Var(0),
            Node::Var(0),
            Node::Sub,
            Node::Div,
            Node::Tanh,
        ];
        assert!(!ev.eval(&p, &d.x, &mut out));
    }

    #[test]
    fn linear_scaling_finds_offset_and_scale() {
        let d = data();
        let p = vec![Node::Var(0), Node::Var(1), Node::Mul];
        let mut out = vec![0.0; d.rows()];
        Evaluator::new().eval(&p, &d.x, &mut out);
        let s = score(&out, &d, true);
        assert!(s.nmse < 1e-28, "{s:?}");
        assert!((s.intercept - 1.0).abs() < 1e-12 && (s.slope - 1.0).abs() < 1e-12);
        let s = score(&out, &d, false);
        assert!(s.nmse > 1e-3);
        // A constant output explains nothing: nmse 1.
        let s = score(&vec![3.0; d.rows()], &d, true);
        assert!((s.nmse - 1.0).abs() < 1e-12 && s.slope == 0.0);
    }
}
