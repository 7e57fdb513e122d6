//! Expression trees as flat postfix arrays, their random generation and the genetic operators
//! (gplearn's crossover, subtree, hoist and point mutation).

use super::node::Node;
use rand::{Rng, RngExt};

/// A postfix expression: every function follows its arguments; the last node is the root.
pub type Program = Vec<Node>;

/// First index of the subtree whose root is `end`.
pub fn subtree_start(p: &[Node], end: usize) -> usize {
    let mut need: isize = 1;
    let mut j = end + 1;
    while need > 0 {
        j -= 1;
        need += p[j].arity() as isize - 1;
    }
    j
}

/// Depth of the tree (a single terminal has depth 0).
pub fn depth(p: &[Node]) -> usize {
    let mut stack: Vec<usize> = Vec::with_capacity(p.len());
    for n in p {
        let d = match n.arity() {
            0 => 0,
            a => {
                let mut m = 0;
                for _ in 0..a {
                    m = m.max(stack.pop().expect("well-formed postfix"));
                }
                m + 1
            }
        };
        stack.push(d);
    }
    stack.pop().unwrap_or(0)
}

/// Whether `p` is one well-formed tree.
pub fn is_valid(p: &[Node], n_vars: usize) -> bool {
    let mut height: isize = 0;
    for n in p {
        if let Node::Var(k) = n {
            if *k as usize >= n_vars {
                return false;
            }
        }
        if let Node::Const(c) = n {
            if !c.is_finite() {
                return false;
            }
        }
        height += 1 - n.arity() as isize;
        if height < 1 {
            return false;
        }
    }
    height == 1
}

/// Indices of the variables a program reads, sorted.
pub fn used_variables(p: &[Node]) -> Vec<usize> {
    let mut v: Vec<usize> = p
        .iter()
        .filter_map(|n| match n {
            Node::Var(k) => Some(*k as usize),
            _ => None,
        })
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// What random trees and mutations may draw from.
#[derive(Clone, Debug)]
pub struct Alphabet {
    /// The function set (non-empty).
    pub functions: Vec<Node>,
    /// Number of input variables: terminals draw `Var(0..n_vars)`.
    pub n_vars: usize,
    /// Range (lo, hi), lo < hi, of freshly drawn constants (gplearn: (-1, 1)); tuning may move
    /// them anywhere.
    pub const_range: (f64, f64),
}

impl Alphabet {
    fn terminal(&self, rng: &mut impl Rng) -> Node {
        // gplearn: a constant is one more choice beside the variables.
        let k = rng.random_range(0..=self.n_vars);
        if k == self.n_vars {
            Node::Const(rng.random_range(self.const_range.0..self.const_range.1))
        } else {
            Node::Var(k as u16)
        }
    }

    fn function_of_arity(&self, arity: usize, rng: &mut impl Rng) -> Option<Node> {
        let n = self.functions.iter().filter(|f| f.arity() == arity).count();
        if n == 0 {
            return None;
        }
        let pick = rng.random_range(0..n);
        self.functions
            .iter()
            .filter(|f| f.arity() == arity)
            .nth(pick)
            .copied()
    }

    /// A random tree by gplearn's "full" (every branch to `max_depth`) or "grow" method.
    pub fn random_tree(&self, max_depth: usize, full: bool, rng: &mut impl Rng) -> Program {
        let mut out = Vec::new();
        self.grow(max_depth, full, true, rng, &mut out);
        out
    }

    fn grow(&self, depth: usize, full: bool, root: bool, rng: &mut impl Rng, out: &mut Program) {
        let n_f = self.functions.len();
        let choose_function = if depth == 0 {
            false
        } else if full || root {
            true
        } else {
            rng.random_range(0..n_f + self.n_vars + 1) < n_f
        };
        if choose_function {
            let f = self.functions[rng.random_range(0..n_f)];
            for _ in 0..f.arity() {
                self.grow(depth - 1, full, false, rng, out);
            }
            out.push(f);
        } else {
            out.push(self.terminal(rng));
        }
    }

    /// Ramped half-and-half: depth uniform in `depths`, full or grow with equal chance.
    pub fn ramped_tree(&self, depths: (usize, usize), rng: &mut impl Rng) -> Program {
        let d = rng.random_range(depths.0..=depths.1);
        let full = rng.random_bool(0.5);
        self.random_tree(d, full, rng)
    }
}

/// A random subtree `(start, end)`, functions weighted 0.9 and terminals 0.1 as in gplearn
/// (Koza's bias towards internal crossover points).
pub fn random_subtree(p: &[Node], rng: &mut impl Rng) -> (usize, usize) {
    let weight = |n: &Node| if n.is_terminal() { 0.1 } else { 0.9 };
    let total: f64 = p.iter().map(weight).sum();
    let mut r = rng.random_range(0.0..total);
    let mut end = p.len() - 1;
    for (i, n) in p.iter().enumerate() {
        r -= weight(n);
        if r < 0.0 {
            end = i;
            break;
        }
    }
    (subtree_start(p, end), end)
}

fn splice(p: &[Node], (s, e): (usize, usize), insert: &[Node]) -> Program {
    let mut out = Vec::with_capacity(p.len() - (e + 1 - s) + insert.len());
    out.extend_from_slice(&p[..s]);
    out.extend_from_slice(insert);
    out.extend_from_slice(&p[e + 1..]);
    out
}

/// Replaces a random subtree of `parent` by a random subtree of `donor`.
pub fn crossover(parent: &[Node], donor: &[Node], rng: &mut impl Rng) -> Program {
    let target = random_subtree(parent, rng);
    let (ds, de) = random_subtree(donor, rng);
    splice(parent, target, &donor[ds..=de])
}

/// Crossover with a freshly generated tree (gplearn's subtree mutation).
pub fn subtree_mutation(
    parent: &[Node],
    alphabet: &Alphabet,
    depths: (usize, usize),
    rng: &mut impl Rng,
) -> Program {
    let donor = alphabet.ramped_tree(depths, rng);
    crossover(parent, &donor, rng)
}

/// Replaces a random subtree by one of its own subtrees: shrinks bloated trees.
pub fn hoist_mutation(parent: &[Node], rng: &mut impl Rng) -> Program {
    let (s, e) = random_subtree(parent, rng);
    let sub = &parent[s..=e];
    let (hs, he) = random_subtree(sub, rng);
    splice(parent, (s, e), &sub[hs..=he])
}

/// Replaces each node with probability `p_replace` by a node of the same arity.
pub fn point_mutation(
    parent: &[Node],
    alphabet: &Alphabet,
    p_replace: f64,
    rng: &mut impl Rng,
) -> Program {
    let mut out = parent.to_vec();
    for n in out.iter_mut() {
        if rng.random_bool(p_replace) {
            *n = match n.arity() {
                0 => alphabet.terminal(rng),
                a => alphabet.function_of_arity(a, rng).unwrap_or(*n),
            };
        }
    }
    out
}

/// Replaces one variable `x` by `x * c`: gives constant tuning a handle inside functions, e.g.
/// `exp(x)` -> `exp(x * c)` (Operon weights every variable for the same reason).
pub fn scale_mutation(parent: &[Node], alphabet: &Alphabet, rng: &mut impl Rng) -> Program {
    let vars: Vec<usize> = (0..parent.len())
        .filter(|&i| matches!(parent[i], Node::Var(_)))
        .collect();
    if vars.is_empty() {
        return parent.to_vec();
    }
    let i = vars[rng.random_range(0..vars.len())];
    let c = rng.random_range(alphabet.const_range.0..alphabet.const_range.1);
    splice(parent, (i, i), &[parent[i], Node::Const(c), Node::Mul])
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    fn alphabet() -> Alphabet {
        Alphabet {
            functions: super::super::node::parse_function_set("add,sub,mul,div,sqrt,log,exp,tanh")
                .unwrap(),
            n_vars: 3,
            const_range: (-1.0, 1.0),
        }
    }

    #[test]
    fn subtree_bounds_of_a_known_tree() {
        // (x0 + x1) * sqrt(x2)
        let p = vec![
            Node::Var(0),
            Node::Var(1),
            Node::Add,
            Node::Var(2),
            Node::Sqrt,
            Node::Mul,
        ];
        assert_eq!(subtree_start(&p, 5), 0);
        assert_eq!(subtree_start(&p, 4), 3);
        assert_eq!(subtree_start(&p, 2), 0);
        assert_eq!(subtree_start(&p, 1), 1);
        assert_eq!(depth(&p), 2);
        assert_eq!(used_variables(&p), vec![0, 1, 2]);
    }

    #[test]
    fn operators_keep_trees_well_formed() {
        let a = alphabet();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        let mut pop: Vec<Program> = (0..200).map(|_| a.ramped_tree((2, 6), &mut rng)).collect();
        for p in &pop {
            assert!(is_valid(p, 3));
            assert!(depth(p) <= 6);
        }
        for i in 0..2000 {
            let child = match i % 5 {
                0 => crossover(&pop[i % 200], &pop[(i * 7) % 200], &mut rng),
                1 => subtree_mutation(&pop[i % 200], &a, (2, 4), &mut rng),
                2 => hoist_mutation(&pop[i % 200], &mut rng),
                3 => point_mutation(&pop[i % 200], &a, 0.3, &mut rng),
                _ => scale_mutation(&pop[i % 200], &a, &mut rng),
            };
            assert!(is_valid(&child, 3), "{child:?}");
            pop[i % 200] = child;
        }
    }

    #[test]
    fn full_trees_reach_their_depth() {
        let a = alphabet();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        for d in 0..5 {
            assert_eq!(depth(&a.random_tree(d, true, &mut rng)), d);
        }
    }
}
