//! A saved model's equation rewritten over another model's inputs: the extended model's part of
//! a model fitted as its extension (`train --extends`), which adds a fitted correction to it.
//!
//! Each equation reads its inputs through its own transforms (a linear or log map onto [0, 1]
//! over its own ranges). The rewritten program reads the new model's variables, recovers the
//! physical value through the new transform's inverse and applies the old one, so that it
//! computes exactly what the old model did at every physical point.

use super::model::{Input, Metamodel, Transform};
use crate::error::{Error, Result};
use mbgc_sr::Node;

/// Nodes computing `old`'s variable from the new model's variable `k` with transform `new`.
fn variable(k: u16, new: &Transform, old: &Transform) -> Vec<Node> {
    // The same scaling (the same range in both spaces): the variable itself, so the old
    // equation reads as it did.
    if new == old {
        return vec![Node::Var(k)];
    }
    // The physical value x from the new variable v.
    let mut out = vec![Node::Var(k)];
    let log_of_x_ready = match *new {
        Transform::Identity => false,
        Transform::Linear { offset, width } => {
            out.extend([
                Node::Const(width),
                Node::Mul,
                Node::Const(offset),
                Node::Add,
            ]);
            false
        }
        // v = (ln x - offset) / width: ln x is at hand, x itself only through exp.
        Transform::Log { offset, width } => {
            out.extend([
                Node::Const(width),
                Node::Mul,
                Node::Const(offset),
                Node::Add,
            ]);
            true
        }
    };
    match *old {
        Transform::Identity => {
            if log_of_x_ready {
                out.push(Node::Exp);
            }
        }
        Transform::Linear { offset, width } => {
            if log_of_x_ready {
                out.push(Node::Exp);
            }
            out.extend([
                Node::Const(offset),
                Node::Sub,
                Node::Const(width),
                Node::Div,
            ]);
        }
        Transform::Log { offset, width } => {
            if !log_of_x_ready {
                out.push(Node::Log);
            }
            out.extend([
                Node::Const(offset),
                Node::Sub,
                Node::Const(width),
                Node::Div,
            ]);
        }
    }
    out
}

/// `base`'s program for response `response` as a program over `inputs` (the new model's, in its
/// order): every input of `base` must be among them, by name.
pub fn rebase_program(base: &Metamodel, response: usize, inputs: &[Input]) -> Result<Vec<Node>> {
    let mut map = Vec::with_capacity(base.inputs.len());
    for b in &base.inputs {
        let k = inputs
            .iter()
            .position(|i| i.name == b.name)
            .ok_or_else(|| {
                Error::invalid(format!(
                    "the extended model reads {}, which is not an input of the new fit; expected \
                 its inputs among the new ones",
                    b.name
                ))
            })?;
        map.push(variable(k as u16, &inputs[k].transform, &b.transform));
    }
    let mut out = Vec::new();
    for node in &base.responses[response].program {
        match *node {
            Node::Var(j) => out.extend(map[j as usize].iter().copied()),
            other => out.push(other),
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mbgc_sr::eval::Evaluator;

    #[test]
    fn every_pair_of_transforms_reads_the_same_physical_value() {
        let transforms = [
            Transform::Identity,
            Transform::Linear {
                offset: 2.0,
                width: 3.0,
            },
            Transform::Log {
                offset: 0.5,
                width: 1.5,
            },
        ];
        for new in &transforms {
            for old in &transforms {
                for x in [2.5_f64, 4.0, 4.9] {
                    let v = new.apply(x);
                    let p = variable(0, new, old);
                    let mut out = [0.0];
                    assert!(Evaluator::new().eval(&p, &[vec![v]], &mut out));
                    let want = old.apply(x);
                    assert!(
                        (out[0] - want).abs() < 1e-12 * want.abs().max(1.0),
                        "{new:?} -> {old:?} at {x}: {} vs {want}",
                        out[0]
                    );
                }
            }
        }
    }
}
