//! Equations as strings that sympy's `sympify` reads with their intended meaning.

use super::names::{ascii_identifier, unique};
use crate::metamodel::{Metamodel, Transform};
use mbgc_sr::expr::{exact_constant, infix, Expr};

/// Names sympify would read as something other than a symbol (constants, functions, keywords).
const TAKEN: &[&str] = &[
    "E",
    "I",
    "N",
    "O",
    "Q",
    "S",
    "pi",
    "oo",
    "beta",
    "gamma",
    "zeta",
    "lambda",
    "Lambda",
    "li",
    "Li",
    "Ei",
    "Si",
    "Ci",
    "rf",
    "ff",
    "re",
    "im",
    "sign",
    "exp",
    "log",
    "sqrt",
    "sin",
    "cos",
    "tan",
    "tanh",
    "and",
    "or",
    "not",
    "is",
    "in",
    "if",
    "else",
    "for",
    "def",
    "class",
    "from",
    "import",
    "as",
    "with",
    "yield",
    "None",
    "True",
    "False",
    "del",
    "pass",
    "lambda",
    "global",
    "range",
    "diff",
    "limit",
    "series",
    "factorial",
    "binomial",
    "var",
    "symbols",
    "Symbol",
];

fn symbol(name: &str) -> String {
    if TAKEN.contains(&name) {
        format!("Symbol('{name}')")
    } else {
        name.to_string()
    }
}

/// The transformed variable as an expression of the physical input, for substitution.
fn definition(name: &str, t: &Transform) -> Option<String> {
    let x = symbol(name);
    match t {
        Transform::Identity => None,
        Transform::Linear { offset, width } => Some(format!(
            "({x} - {})/{}",
            exact_constant(*offset),
            exact_constant(*width)
        )),
        Transform::Log { offset, width } => Some(format!(
            "(log({x}) - {})/{}",
            exact_constant(*offset),
            exact_constant(*width)
        )),
    }
}

/// The inputs' names as distinct Python identifiers (`x-y` would read as x minus y).
pub fn input_names(m: &Metamodel) -> Vec<String> {
    unique(&m.input_names(), ascii_identifier, &[])
}

/// The equation of one response in the physical inputs (transforms substituted).
pub fn equation(m: &Metamodel, response: usize) -> String {
    let names: Vec<String> = m
        .inputs
        .iter()
        .zip(input_names(m))
        .map(|(i, name)| match definition(&name, &i.transform) {
            Some(d) => format!("({d})"),
            None => symbol(&name),
        })
        .collect();
    infix(
        &Expr::from_postfix(&m.responses[response].program),
        &names,
        &exact_constant,
    )
}

/// `name = expression` per response, one per line.
pub fn lines(m: &Metamodel) -> String {
    let names: Vec<String> = m.responses.iter().map(|r| r.name.clone()).collect();
    unique(&names, ascii_identifier, &[])
        .iter()
        .enumerate()
        .map(|(r, name)| format!("{name} = {}\n", equation(m, r)))
        .collect()
}
