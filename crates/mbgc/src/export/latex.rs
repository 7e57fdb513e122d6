//! Equations as LaTeX, constants rounded to four significant digits, names in the field's
//! notation (`mu_r_pp` -> `\mu_{r,pp}`, `d50` -> `d_{50}`).

use crate::metamodel::{Metamodel, Transform};
use mbgc_sr::expr::Expr;
use mbgc_sr::Node;

const GREEK: &[&str] = &[
    "alpha", "beta", "gamma", "delta", "epsilon", "zeta", "eta", "theta", "iota", "kappa",
    "lambda", "mu", "nu", "xi", "pi", "rho", "sigma", "tau", "upsilon", "phi", "chi", "psi",
    "omega", "Gamma", "Delta", "Theta", "Lambda", "Xi", "Pi", "Sigma", "Phi", "Psi", "Omega",
];

/// Text that LaTeX prints as written: its special characters escaped.
fn escape(s: &str) -> String {
    s.chars()
        .map(|c| match c {
            '_' | '%' | '&' | '#' | '$' | '{' | '}' => format!("\\{c}"),
            '\\' => "\\textbackslash{}".to_string(),
            '~' => "\\textasciitilde{}".to_string(),
            '^' => "\\textasciicircum{}".to_string(),
            c if c.is_control() => " ".to_string(),
            c => c.to_string(),
        })
        .collect()
}

fn base(b: &str) -> String {
    if GREEK.contains(&b) {
        format!("\\{b}")
    } else if b.chars().count() == 1 && b.chars().all(|c| c.is_ascii_alphanumeric()) {
        b.to_string()
    } else {
        format!("\\mathrm{{{}}}", escape(b))
    }
}

/// `mu_r_pp` -> `\mu_{r,pp}`; `d50` -> `d_{50}`; `E_p` -> `E_{p}`.
pub fn symbol(name: &str) -> String {
    let mut parts = name.split('_');
    let head = parts.next().unwrap_or("");
    // A name made of words (`shear_angle`) is text, not a symbol with subscripts.
    let is_word = |w: &str| w.chars().count() > 2 && w.chars().all(|c| c.is_ascii_alphabetic());
    if !GREEK.contains(&head) && is_word(head) && name.split('_').skip(1).all(is_word) {
        let words: Vec<String> = name.split('_').map(escape).collect();
        return format!("\\mathrm{{{}}}", words.join("\\ "));
    }
    let mut subs: Vec<String> = parts.filter(|p| !p.is_empty()).map(escape).collect();
    let split = head.find(|c: char| c.is_ascii_digit()).filter(|&i| i > 0);
    let b = match split {
        Some(i) => {
            subs.insert(0, escape(&head[i..]));
            base(&head[..i])
        }
        None => base(head),
    };
    if subs.is_empty() {
        b
    } else {
        format!("{b}_{{{}}}", subs.join(","))
    }
}

/// Four significant digits; powers of ten outside [1e-3, 1e4).
pub fn constant(v: f64) -> String {
    match crate::numeric::four_significant(v) {
        (m, None) => m,
        (m, Some(e)) => format!("{m} \\times 10^{{{e}}}"),
    }
}

fn latex(e: &Expr, names: &[String]) -> (String, u8) {
    // Precedence: 1 sum, 2 product, 3 unary minus, 5 atom.
    let wrap = |(s, p): (String, u8), min: u8| {
        if p < min {
            format!("\\left({s}\\right)")
        } else {
            s
        }
    };
    match e {
        Expr::Var(k) => (names[*k as usize].clone(), 5),
        Expr::Const(v) => (constant(*v), if *v < 0.0 { 3 } else { 5 }),
        Expr::Unary(f, a) => {
            let inner = latex(a, names);
            match f {
                Node::Neg => (format!("-{}", wrap(inner, 4)), 3),
                Node::Square => (format!("{}^{{2}}", wrap(inner, 5)), 5),
                Node::Cube => (format!("{}^{{3}}", wrap(inner, 5)), 5),
                Node::Sqrt => (format!("\\sqrt{{{}}}", inner.0), 5),
                Node::Log => (format!("\\ln\\left({}\\right)", inner.0), 5),
                Node::Exp => (format!("\\exp\\left({}\\right)", inner.0), 5),
                Node::Tanh => (format!("\\tanh\\left({}\\right)", inner.0), 5),
                Node::Sin => (format!("\\sin\\left({}\\right)", inner.0), 5),
                Node::Cos => (format!("\\cos\\left({}\\right)", inner.0), 5),
                _ => unreachable!(),
            }
        }
        Expr::Binary(f, a, b) => {
            let (la, lb) = (latex(a, names), latex(b, names));
            match f {
                Node::Add if matches!(**b, Expr::Const(v) if v < 0.0) => {
                    let Expr::Const(v) = **b else { unreachable!() };
                    (format!("{} - {}", la.0, constant(-v)), 1)
                }
                // `a + -b` reads as `a - b`; a term of precedence 3 starts with its sign.
                Node::Add if lb.1 == 3 && lb.0.starts_with('-') => {
                    (format!("{} - {}", la.0, &lb.0[1..]), 1)
                }
                Node::Add => (format!("{} + {}", la.0, wrap(lb, 2)), 1),
                Node::Sub if lb.1 == 3 && lb.0.starts_with('-') => {
                    (format!("{} + {}", la.0, &lb.0[1..]), 1)
                }
                Node::Sub => (format!("{} - {}", la.0, wrap(lb, 2)), 1),
                _ => product(e, names),
            }
        }
    }
}

/// Gathers a product/quotient chain into a coefficient, numerator and denominator factors.
fn gather<'a>(
    e: &'a Expr,
    inv: bool,
    coef: &mut f64,
    num: &mut Vec<&'a Expr>,
    den: &mut Vec<&'a Expr>,
) {
    match e {
        Expr::Binary(Node::Mul, a, b) => {
            gather(a, inv, coef, num, den);
            gather(b, inv, coef, num, den);
        }
        Expr::Binary(Node::Div, a, b) => {
            gather(a, inv, coef, num, den);
            gather(b, !inv, coef, num, den);
        }
        Expr::Const(c) => *coef = if inv { *coef / c } else { *coef * c },
        f if inv => den.push(f),
        f => num.push(f),
    }
}

/// Factors with equal ones written as powers: `r \, r` -> `r^{2}`. A sum is parenthesised
/// unless it stands alone (`alone`: the whole numerator or denominator of a fraction).
fn factors(list: &[&Expr], names: &[String], alone: bool) -> String {
    let mut seen: Vec<(&Expr, usize)> = Vec::new();
    for f in list {
        match seen.iter_mut().find(|(g, _)| g == f) {
            Some((_, k)) => *k += 1,
            None => seen.push((f, 1)),
        }
    }
    seen.iter()
        .map(|(f, k)| {
            let (s, p) = latex(f, names);
            let s = if p < 5 && (*k > 1 || seen.len() > 1 || !alone) {
                format!("\\left({s}\\right)")
            } else {
                s
            };
            if *k > 1 {
                format!("{s}^{{{k}}}")
            } else {
                s
            }
        })
        .collect::<Vec<_>>()
        .join(" \\, ")
}

/// `c \frac{a b}{d}`: how people write products and quotients (for reading; the rounding of
/// the coefficient is the only change).
fn product(e: &Expr, names: &[String]) -> (String, u8) {
    let (mut coef, mut num, mut den) = (1.0, Vec::new(), Vec::new());
    gather(e, false, &mut coef, &mut num, &mut den);
    let (sign, c) = if coef < 0.0 { ("-", -coef) } else { ("", coef) };
    // A lone numerator is its own term only without a coefficient or sign in front of it.
    let bare = den.is_empty() && c == 1.0 && sign.is_empty();
    let top = if num.is_empty() {
        "1".to_string()
    } else {
        factors(&num, names, !den.is_empty() || bare)
    };
    let body = if den.is_empty() {
        top
    } else {
        format!("\\frac{{{top}}}{{{}}}", factors(&den, names, true))
    };
    let prec = if sign.is_empty() { 2 } else { 3 };
    if c == 1.0 {
        if num.is_empty() && den.is_empty() {
            return (format!("{sign}1"), prec);
        }
        (format!("{sign}{body}"), prec)
    } else if num.is_empty() && den.is_empty() {
        (constant(coef), prec)
    } else if num.is_empty() && body == "1" {
        (format!("{sign}{}", constant(c)), prec)
    } else {
        let body = if num.is_empty() && !den.is_empty() {
            format!(
                "\\frac{{{}}}{{{}}}",
                constant(c),
                factors(&den, names, true)
            )
        } else {
            format!("{} \\, {body}", constant(c))
        };
        (format!("{sign}{body}"), prec)
    }
}

/// A scaling that changes nothing (`Linear` with offset 0 and width 1, a parameter whose range
/// is already [0, 1]) is written as the input itself, not as `(x - 0)/1`.
fn is_identity(t: &Transform) -> bool {
    match *t {
        Transform::Identity => true,
        Transform::Linear { offset, width } => offset == 0.0 && width == 1.0,
        Transform::Log { .. } => false,
    }
}

/// The right-hand side of one response's equation.
pub fn equation(m: &Metamodel, response: usize) -> String {
    let names: Vec<String> = m
        .inputs
        .iter()
        .map(|i| {
            if is_identity(&i.transform) {
                symbol(&i.name)
            } else {
                format!("\\tilde{{{}}}", symbol(&i.name))
            }
        })
        .collect();
    latex(&display_tree(m, response), &names).0
}

/// The equation as a reader is shown it: simplified (constants folded, `(a + c1) - c2` as
/// `a + c`, division by a constant as a product) when the simplified tree gives the saved
/// equation's values to 1e-9 at 64 points spread over the model's domain; the saved tree
/// otherwise, so that the display never says something the model does not.
pub fn display_tree(m: &Metamodel, response: usize) -> Expr {
    let saved = &m.responses[response];
    let e = Expr::from_postfix(&saved.program);
    let s = e.clone().simplify();
    if s == e {
        return e;
    }
    let n = 64;
    let x: Vec<Vec<f64>> = m
        .inputs
        .iter()
        .enumerate()
        .map(|(j, i)| {
            // A different irrational stride per input spreads the points over the box.
            let stride = (0.618_033_988_75 + 0.414_213_562 * j as f64).fract();
            (0..n)
                .map(|k| {
                    let u = ((k as f64 + 0.5) * stride).fract();
                    i.domain[0] + u * (i.domain[1] - i.domain[0])
                })
                .collect()
        })
        .collect();
    let mut simplified = saved.clone();
    simplified.program = s.to_postfix();
    let (a, b) = (m.predict(saved, &x), m.predict(&simplified, &x));
    let same = a
        .iter()
        .zip(&b)
        .all(|(a, b)| (a.is_nan() && b.is_nan()) || (a - b).abs() <= 1e-9 * a.abs().max(1.0));
    if same {
        s
    } else {
        e
    }
}

/// The equation as printed: [`display_tree`] with every constant rounded to the four
/// significant digits [`constant`] writes, as a program over the model's scaled inputs. A reader
/// who copies the printed equation computes this, so its accuracy is reported beside the saved
/// equation's.
pub fn printed_program(m: &Metamodel, response: usize) -> Vec<Node> {
    fn round(e: Expr) -> Expr {
        match e {
            Expr::Const(c) => Expr::Const(crate::numeric::round_significant(c, 4)),
            Expr::Unary(f, a) => Expr::Unary(f, Box::new(round(*a))),
            Expr::Binary(f, a, b) => Expr::Binary(f, Box::new(round(*a)), Box::new(round(*b))),
            v => v,
        }
    }
    round(display_tree(m, response)).to_postfix()
}

/// An `align*` block with every response and the definitions of scaled inputs.
pub fn document(m: &Metamodel) -> String {
    let mut out = String::from("\\begin{align*}\n");
    let mut rows: Vec<String> = (0..m.responses.len())
        .map(|r| format!("{} &= {}", symbol(&m.responses[r].name), equation(m, r)))
        .collect();
    for i in &m.inputs {
        let s = symbol(&i.name);
        match i.transform {
            _ if is_identity(&i.transform) => {}
            Transform::Identity => {}
            Transform::Linear { offset, width } => rows.push(format!(
                "\\tilde{{{s}}} &= \\frac{{{s} - {}}}{{{}}}",
                constant(offset),
                constant(width)
            )),
            Transform::Log { offset, width } => rows.push(format!(
                "\\tilde{{{s}}} &= \\frac{{\\ln {s} - {}}}{{{}}}",
                constant(offset),
                constant(width)
            )),
        }
    }
    out.push_str(&rows.join(" \\\\\n"));
    out.push_str("\n\\end{align*}\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use Expr::{Binary, Const, Var};

    /// The shipped model's group term was shown as `... + 4.624 - 9.193`: the display folds it,
    /// and the folded tree gives the saved equation's values.
    #[test]
    fn the_display_folds_constants_the_saved_equation_leaves_apart() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let m = Metamodel::load(&root.join("models/shear_box.json")).unwrap();
        let k = m
            .responses
            .iter()
            .position(|r| r.name == "bulk_density")
            .unwrap();
        let shown = equation(&m, k);
        assert!(
            shown.contains("\\ln\\left(d_{50}\\right) - 4.569"),
            "{shown}"
        );
        assert!(
            !shown.contains("4.624") && !shown.contains("9.193"),
            "{shown}"
        );
        let names: Vec<String> = m.inputs.iter().map(|i| symbol(&i.name)).collect();
        let raw = latex(&Expr::from_postfix(&m.responses[k].program), &names).0;
        assert!(raw.contains("+ 4.624 - 9.193"), "{raw}");
    }

    /// The printed equation is the displayed tree with the printed digits: a reader who copies
    /// it computes exactly these constants.
    #[test]
    fn the_printed_program_carries_the_printed_digits() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
        let m = Metamodel::load(&root.join("models/shear_box.json")).unwrap();
        for k in 0..m.responses.len() {
            let shown = display_tree(&m, k).to_postfix();
            let printed = printed_program(&m, k);
            assert_eq!(shown.len(), printed.len());
            let mut rounded = 0;
            for (a, b) in shown.iter().zip(&printed) {
                match (a, b) {
                    (Node::Const(a), Node::Const(b)) => {
                        assert_eq!(format!("{:.3e}", a).parse::<f64>().unwrap(), *b);
                        rounded += usize::from(a != b);
                    }
                    _ => assert_eq!(a, b),
                }
            }
            assert!(rounded > 0, "the saved constants carry more than 4 digits");
        }
    }

    #[test]
    fn names_follow_the_field() {
        assert_eq!(symbol("mu_r_pp"), "\\mu_{r,pp}");
        assert_eq!(symbol("d50"), "d_{50}");
        assert_eq!(symbol("E_p"), "E_{p}");
        assert_eq!(symbol("shear_angle"), "\\mathrm{shear\\ angle}");
        assert_eq!(symbol("flow_rate_t1"), "\\mathrm{flow}_{rate,t1}");
        assert_eq!(symbol("sigma_ln"), "\\sigma_{ln}");
    }

    #[test]
    fn constants_are_rounded_to_four_digits() {
        assert_eq!(constant(0.07957747154594767), "0.07958");
        assert_eq!(constant(1.4999999999999991), "1.5");
        assert_eq!(constant(-2.3), "-2.3");
        assert_eq!(constant(1234.5678), "1235");
        assert_eq!(constant(6.02e23), "6.020 \\times 10^{23}");
        assert_eq!(constant(-1.5e-5), "-1.500 \\times 10^{-5}");
    }

    fn tex(e: Expr) -> String {
        let names = ["x", "y", "z"].map(String::from);
        latex(&e, &names).0
    }

    fn b(f: Node, a: Expr, c: Expr) -> Expr {
        Binary(f, Box::new(a), Box::new(c))
    }

    #[test]
    fn a_sum_times_a_constant_keeps_its_parentheses() {
        // (x + y) * 3: once printed as `3 \, x + y`, which is 3x + y.
        let sum = || b(Node::Add, Var(0), Var(1));
        assert_eq!(
            tex(b(Node::Mul, sum(), Const(3.0))),
            "3 \\, \\left(x + y\\right)"
        );
        assert_eq!(
            tex(b(Node::Mul, sum(), Const(-3.0))),
            "-3 \\, \\left(x + y\\right)"
        );
        // A sum alone over a denominator needs none.
        assert_eq!(tex(b(Node::Div, sum(), Var(2))), "\\frac{x + y}{z}");
        assert_eq!(
            tex(b(Node::Div, sum(), Const(2.0))),
            "0.5 \\, \\left(x + y\\right)"
        );
        // (x + y / (z * -2)) * 4 + 1: the coefficient multiplies both terms of the sum.
        let inner = b(
            Node::Add,
            Var(0),
            b(Node::Div, Var(1), b(Node::Mul, Var(2), Const(-2.0))),
        );
        assert_eq!(
            tex(b(Node::Add, b(Node::Mul, inner, Const(4.0)), Const(1.0))),
            "4 \\, \\left(x - 0.5 \\, \\frac{y}{z}\\right) + 1"
        );
        // x - (-2 y) reads x + 2 y.
        assert_eq!(
            tex(b(Node::Sub, Var(0), b(Node::Mul, Var(1), Const(-2.0)))),
            "x + 2 \\, y"
        );
    }
}
