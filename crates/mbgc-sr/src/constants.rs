//! Constant tuning: Levenberg-Marquardt on a program's constants (and its output scaling), with
//! the Jacobian from reverse-mode differentiation of the postfix tree, batch by batch.

use super::eval::{all_finite, score, Dataset, Evaluator, Score, BATCH};
use super::node::Node;
use nalgebra::{DMatrix, DVector};

/// Children `(left, right)` of every node; unary nodes use `left`, leaves neither.
pub(crate) fn children(p: &[Node]) -> Vec<(usize, usize)> {
    let mut stack = Vec::with_capacity(p.len());
    let mut out = Vec::with_capacity(p.len());
    for (i, n) in p.iter().enumerate() {
        let c = match n.arity() {
            0 => (usize::MAX, usize::MAX),
            1 => (stack.pop().expect("postfix"), usize::MAX),
            _ => {
                let r = stack.pop().expect("postfix");
                (stack.pop().expect("postfix"), r)
            }
        };
        out.push(c);
        stack.push(i);
    }
    out
}

/// Scratch buffers for one thread.
#[derive(Default)]
pub struct Tuner {
    value: Vec<[f64; BATCH]>,
    adjoint: Vec<[f64; BATCH]>,
    pred: Vec<f64>,
    eval: Evaluator,
    traced: u64,
}

impl Tuner {
    /// Empty buffers, grown on first use.
    pub fn new() -> Tuner {
        Tuner::default()
    }

    /// Nodes times rows evaluated (forward, and reverse counted as one more).
    pub fn node_evals(&self) -> u64 {
        self.eval.node_evals + self.traced
    }

    /// Forward pass of one batch keeping every node's value; `false` on a non-finite value.
    fn forward(
        &mut self,
        p: &[Node],
        ch: &[(usize, usize)],
        x: &[Vec<f64>],
        r0: usize,
        m: usize,
    ) -> bool {
        for (i, &node) in p.iter().enumerate() {
            let (l, r) = ch[i];
            let (done, rest) = self.value.split_at_mut(i);
            let v = &mut rest[0][..m];
            match node {
                Node::Var(k) => v.copy_from_slice(&x[k as usize][r0..r0 + m]),
                Node::Const(c) => v.fill(c),
                Node::Add | Node::Sub | Node::Mul | Node::Div => {
                    let (a, b) = (&done[l][..m], &done[r][..m]);
                    for j in 0..m {
                        v[j] = node.binary(a[j], b[j]);
                    }
                }
                f => {
                    let a = &done[l][..m];
                    for j in 0..m {
                        v[j] = f.unary(a[j]);
                    }
                }
            }
            if !all_finite(v) {
                return false;
            }
        }
        true
    }

    /// Reverse pass: d root / d node for every node of the batch (each node has one parent).
    fn backward(&mut self, p: &[Node], ch: &[(usize, usize)], m: usize) {
        let last = p.len() - 1;
        self.adjoint[last][..m].fill(1.0);
        for i in (0..p.len()).rev() {
            let (l, r) = ch[i];
            let node = p[i];
            if node.is_terminal() {
                continue;
            }
            let (lo, hi) = self.adjoint.split_at_mut(i);
            let g = &hi[0];
            let val = &self.value;
            for j in 0..m {
                let gi = g[j];
                match node {
                    Node::Add => {
                        lo[l][j] = gi;
                        lo[r][j] = gi;
                    }
                    Node::Sub => {
                        lo[l][j] = gi;
                        lo[r][j] = -gi;
                    }
                    Node::Mul => {
                        lo[l][j] = gi * val[r][j];
                        lo[r][j] = gi * val[l][j];
                    }
                    Node::Div => {
                        lo[l][j] = gi / val[r][j];
                        lo[r][j] = -gi * val[i][j] / val[r][j];
                    }
                    Node::Neg => lo[l][j] = -gi,
                    Node::Square => lo[l][j] = 2.0 * gi * val[l][j],
                    Node::Cube => lo[l][j] = 3.0 * gi * val[l][j] * val[l][j],
                    Node::Sqrt => lo[l][j] = 0.5 * gi / val[i][j],
                    Node::Log => lo[l][j] = gi / val[l][j],
                    Node::Exp => lo[l][j] = gi * val[i][j],
                    Node::Tanh => lo[l][j] = gi * (1.0 - val[i][j] * val[i][j]),
                    Node::Sin => lo[l][j] = gi * val[l][j].cos(),
                    Node::Cos => lo[l][j] = -gi * val[l][j].sin(),
                    Node::Var(_) | Node::Const(_) => unreachable!(),
                }
            }
        }
    }

    /// Tunes the constants of `p` in place by at most `iterations` Levenberg-Marquardt steps and
    /// returns its score on `data`. With `linear_scaling`, intercept and slope are fitted jointly.
    pub fn tune(
        &mut self,
        p: &mut [Node],
        data: &Dataset,
        linear_scaling: bool,
        iterations: usize,
    ) -> Score {
        let n = data.rows();
        self.pred.resize(n, 0.0);
        if !self.eval.eval(p, &data.x, &mut self.pred) {
            return Score::INVALID;
        }
        let mut best = score(&self.pred, data, linear_scaling);
        let consts: Vec<usize> = (0..p.len())
            .filter(|&i| matches!(p[i], Node::Const(_)))
            .collect();
        if consts.is_empty() || !best.is_valid() || best.nmse < 1e-28 {
            return best;
        }
        let ch = children(p);
        if self.value.len() < p.len() {
            self.value.resize(p.len(), [0.0; BATCH]);
            self.adjoint.resize(p.len(), [0.0; BATCH]);
        }
        let k = consts.len() + 2;
        let mut lambda = 1e-3;
        let sse_of = |s: &Score| s.nmse * n as f64 * data.y_var();
        let mut sse = sse_of(&best);
        let (mut a, mut b) = (best.intercept, best.slope);
        if !linear_scaling {
            (a, b) = (0.0, 1.0);
        }
        let mut jtj = DMatrix::<f64>::zeros(k, k);
        let mut jtr = DVector::<f64>::zeros(k);
        let mut g = vec![0.0; k];
        for _ in 0..iterations {
            jtj.fill(0.0);
            jtr.fill(0.0);
            let mut r0 = 0;
            while r0 < n {
                let m = BATCH.min(n - r0);
                if !self.forward(p, &ch, &data.x, r0, m) {
                    return best;
                }
                self.backward(p, &ch, m);
                self.traced += (2 * p.len() * m) as u64;
                let root = p.len() - 1;
                for j in 0..m {
                    let f = self.value[root][j];
                    for (q, &ci) in consts.iter().enumerate() {
                        g[q] = b * self.adjoint[ci][j];
                    }
                    g[k - 2] = 1.0;
                    g[k - 1] = f;
                    let res = data.y[r0 + j] - a - b * f;
                    for u in 0..k {
                        jtr[u] += g[u] * res;
                        for v in 0..=u {
                            jtj[(u, v)] += g[u] * g[v];
                        }
                    }
                }
                r0 += m;
            }
            for u in 0..k {
                for v in 0..u {
                    jtj[(v, u)] = jtj[(u, v)];
                }
            }
            if !linear_scaling {
                // Intercept and slope stay at 0 and 1: decouple their rows.
                for u in k - 2..k {
                    for v in 0..k {
                        jtj[(u, v)] = 0.0;
                        jtj[(v, u)] = 0.0;
                    }
                    jtj[(u, u)] = 1.0;
                    jtr[u] = 0.0;
                }
            }
            let mut improved = false;
            for _ in 0..8 {
                let mut lhs = jtj.clone();
                for u in 0..k {
                    lhs[(u, u)] += lambda * jtj[(u, u)].max(1e-12);
                }
                let Some(chol) = lhs.cholesky() else {
                    lambda *= 10.0;
                    continue;
                };
                let step = chol.solve(&jtr);
                let old: Vec<Node> = consts.iter().map(|&i| p[i]).collect();
                for (q, &ci) in consts.iter().enumerate() {
                    if let Node::Const(c) = p[ci] {
                        p[ci] = Node::Const(c + step[q]);
                    }
                }
                let (na, nb) = (a + step[k - 2], b + step[k - 1]);
                let trial = if consts
                    .iter()
                    .all(|&i| matches!(p[i], Node::Const(c) if c.is_finite()))
                    && self.eval.eval(p, &data.x, &mut self.pred)
                {
                    let res: f64 = self
                        .pred
                        .iter()
                        .zip(&data.y)
                        .map(|(f, y)| (y - na - nb * f).powi(2))
                        .sum();
                    if res.is_finite() {
                        res
                    } else {
                        f64::INFINITY
                    }
                } else {
                    f64::INFINITY
                };
                if trial < sse {
                    sse = trial;
                    (a, b) = (na, nb);
                    lambda = (lambda / 3.0).max(1e-12);
                    improved = true;
                    break;
                }
                for (q, &ci) in consts.iter().enumerate() {
                    p[ci] = old[q];
                }
                lambda *= 4.0;
            }
            if !improved || sse <= 1e-28 * n as f64 * data.y_var() {
                break;
            }
        }
        // Rescore the final constants: the linear scaling is re-derived, so it can only improve.
        if self.eval.eval(p, &data.x, &mut self.pred) {
            let s = score(&self.pred, data, linear_scaling);
            if s.nmse <= best.nmse {
                best = s;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recovers_constants_of_a_known_form() {
        // y = 2.5 exp(-0.7 x0) + x1 / 1.3, started from wrong constants.
        let x0: Vec<f64> = (0..200).map(|i| i as f64 * 0.02).collect();
        let x1: Vec<f64> = (0..200).map(|i| ((i * 37) % 200) as f64 * 0.01).collect();
        let y = x0
            .iter()
            .zip(&x1)
            .map(|(a, b)| 2.5 * (-0.7 * a).exp() + b / 1.3)
            .collect();
        let d = Dataset::new(vec![x0, x1], y);
        let mut p = vec![
            Node::Const(1.0),
            Node::Const(-0.2),
            Node::Var(0),
            Node::Mul,
            Node::Exp,
            Node::Mul,
            Node::Var(1),
            Node::Const(0.5),
            Node::Div,
            Node::Add,
        ];
        let mut t = Tuner::new();
        let s = t.tune(&mut p, &d, false, 100);
        assert!(s.nmse < 1e-20, "{s:?} {p:?}");
        assert!(matches!(p[1], Node::Const(c) if (c + 0.7).abs() < 1e-8));
        assert!(matches!(p[7], Node::Const(c) if (c - 1.3).abs() < 1e-8));
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let x0: Vec<f64> = (0..70).map(|i| 0.1 + i as f64 * 0.05).collect();
        let d = Dataset::new(vec![x0.clone()], x0.clone());
        // tanh(c0 * x0) / sqrt(c1 + x0) + log(c2 * x0) * cube(x0 - c3)
        let c = [0.8, 1.5, 2.0, 0.3];
        let build = |c: &[f64]| {
            vec![
                Node::Const(c[0]),
                Node::Var(0),
                Node::Mul,
                Node::Tanh,
                Node::Const(c[1]),
                Node::Var(0),
                Node::Add,
                Node::Sqrt,
                Node::Div,
                Node::Const(c[2]),
                Node::Var(0),
                Node::Mul,
                Node::Log,
                Node::Var(0),
                Node::Const(c[3]),
                Node::Sub,
                Node::Cube,
                Node::Mul,
                Node::Add,
            ]
        };
        let p = build(&c);
        let idx = [0usize, 4, 9, 14];
        let ch = children(&p);
        let mut t = Tuner::new();
        t.value.resize(p.len(), [0.0; BATCH]);
        t.adjoint.resize(p.len(), [0.0; BATCH]);
        assert!(t.forward(&p, &ch, &d.x, 0, BATCH));
        t.backward(&p, &ch, BATCH);
        let mut ev = Evaluator::new();
        for (q, &ci) in idx.iter().enumerate() {
            let h = 1e-6;
            let (mut cp, mut cm) = (c, c);
            cp[q] += h;
            cm[q] -= h;
            let (mut fp, mut fm) = (vec![0.0; 70], vec![0.0; 70]);
            ev.eval(&build(&cp), &d.x, &mut fp);
            ev.eval(&build(&cm), &d.x, &mut fm);
            for j in 0..BATCH {
                let fd = (fp[j] - fm[j]) / (2.0 * h);
                let ad = t.adjoint[ci][j];
                assert!(
                    (fd - ad).abs() < 1e-6 * (1.0 + ad.abs()),
                    "const {q} row {j}: {fd} vs {ad}"
                );
            }
        }
    }
}
