//! Dimensional similarity of an experiment: the dimensionless groups through which some of its
//! inputs act, and the responses that are a known factor times a dimensionless function.
//!
//! An experiment declares it ([`crate::experiments::Experiment::similarity`]); `mbgc fit`
//! and `mbgc train` then fit the equations in the groups (fewer, sharper variables) and compose
//! them back into equations of the physical inputs, so that predictions, gradients and exports
//! stay plain functions of what a user calibrates. The shear box without cohesion is the example:
//! E_p, rho_p and d50 act only through K_p = E_p / (rho_p g d50), and the bulk density is
//! rho_p times a solid fraction.

use mbgc_sr::Node;
use serde::{Deserialize, Serialize};

/// `coefficient * prod(input^power)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Monomial {
    /// Constant factor; carries physical constants and unit conversions (e.g. 1 / (9.81e-3) for g
    /// in m/s^2 with d50 in mm).
    pub coefficient: f64,
    /// `(input name, exponent)` pairs; inputs must be positive where the monomial is evaluated.
    pub powers: Vec<(String, f64)>,
}

impl Monomial {
    /// Its value at a point; `value(name)` gives each input's value.
    pub fn value(&self, value: impl Fn(&str) -> f64) -> f64 {
        self.powers
            .iter()
            .fold(self.coefficient, |acc, (n, p)| acc * value(n).powf(*p))
    }

    /// Whether `input` is one of its factors.
    pub fn contains(&self, input: &str) -> bool {
        self.powers.iter().any(|(n, _)| n == input)
    }

    /// `d ln(monomial) / d input` at a point (zero for an input it does not contain).
    pub fn log_derivative(&self, input: &str, x: f64) -> f64 {
        self.powers
            .iter()
            .filter(|(n, _)| n == input)
            .map(|(_, p)| p / x)
            .sum()
    }

    /// Readable form such as `101.9 E_p / (rho_p d50)`, coefficient to four significant digits.
    pub fn text(&self) -> String {
        let mut num = Vec::new();
        let mut den = Vec::new();
        for (n, p) in &self.powers {
            let (side, q) = if *p < 0.0 {
                (&mut den, -p)
            } else {
                (&mut num, *p)
            };
            side.push(if q == 1.0 {
                n.clone()
            } else {
                format!("{n}^{q}")
            });
        }
        let mut s = if self.coefficient == 1.0 {
            String::new()
        } else {
            // Four significant digits: the text is for reading, the exact value is `coefficient`.
            match crate::numeric::four_significant(self.coefficient) {
                (m, None) => format!("{m} "),
                (m, Some(e)) => format!("{m}e{e} "),
            }
        };
        s.push_str(&if num.is_empty() {
            "1".into()
        } else {
            num.join(" ")
        });
        if !den.is_empty() {
            s.push_str(&format!(" / ({})", den.join(" ")));
        }
        s
    }

    /// Postfix nodes computing `ln(monomial)` from the raw inputs (`var(name)` gives the variable
    /// index of an input whose transform is the identity).
    pub fn ln_program(&self, var: &impl Fn(&str) -> u16) -> Vec<Node> {
        let mut out = Vec::new();
        for (k, (n, p)) in self.powers.iter().enumerate() {
            out.extend([Node::Var(var(n)), Node::Log]);
            if p.abs() != 1.0 {
                out.extend([Node::Const(p.abs()), Node::Mul]);
            }
            if k > 0 {
                out.push(if *p < 0.0 { Node::Sub } else { Node::Add });
            } else if *p < 0.0 {
                out.push(Node::Neg);
            }
        }
        if self.coefficient != 1.0 || self.powers.is_empty() {
            out.push(Node::Const(self.coefficient.ln()));
            if !self.powers.is_empty() {
                out.push(Node::Add);
            }
        }
        out
    }

    /// Postfix nodes computing the monomial as a plain product and quotient of its factors with
    /// powers +-1, times `exp(ln ...)` of the others and its coefficient: exact where a factor of
    /// power 1 is zero (a cohesion off), which [`Monomial::program`]'s logarithm is not, and with
    /// a finite gradient there. `None` without a factor of power 1 to lead the product.
    pub fn product_program(&self, var: &impl Fn(&str) -> u16) -> Option<Vec<Node>> {
        let first = self.powers.iter().position(|(_, p)| *p == 1.0)?;
        let mut out = vec![Node::Var(var(&self.powers[first].0))];
        for (k, (n, p)) in self.powers.iter().enumerate() {
            if k == first || p.abs() != 1.0 {
                continue;
            }
            out.push(Node::Var(var(n)));
            out.push(if *p > 0.0 { Node::Mul } else { Node::Div });
        }
        let rest = Monomial {
            coefficient: 1.0,
            powers: self
                .powers
                .iter()
                .filter(|(_, p)| p.abs() != 1.0)
                .cloned()
                .collect(),
        };
        if !rest.powers.is_empty() {
            out.extend(rest.ln_program(var));
            out.extend([Node::Exp, Node::Mul]);
        }
        if self.coefficient != 1.0 {
            out.extend([Node::Const(self.coefficient), Node::Mul]);
        }
        Some(out)
    }

    /// Postfix nodes computing the monomial itself: the plain product for powers of +-1 and a
    /// coefficient of 1, else `exp(ln ...)`.
    pub fn program(&self, var: &impl Fn(&str) -> u16) -> Vec<Node> {
        let simple = self.coefficient == 1.0
            && !self.powers.is_empty()
            && self.powers[0].1 == 1.0
            && self.powers.iter().all(|(_, p)| p.abs() == 1.0);
        if !simple {
            let mut v = self.ln_program(var);
            v.push(Node::Exp);
            return v;
        }
        let mut out = vec![Node::Var(var(&self.powers[0].0))];
        for (n, p) in &self.powers[1..] {
            out.push(Node::Var(var(n)));
            out.push(if *p > 0.0 { Node::Mul } else { Node::Div });
        }
        out
    }
}

/// A dimensionless group, e.g. `K_p = E_p / (rho_p g d50)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Group {
    /// Name of the group as a fitting variable (e.g. `K_p`).
    pub name: String,
    /// Its physical meaning, for reports.
    pub what: String,
    /// The group as a monomial of the physical inputs; dimensionless by construction.
    pub monomial: Monomial,
}

/// A response that is `factor * fitted`, with `fitted` dimensionless (e.g. the bulk density is
/// rho_p times the solid fraction).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScaledResponse {
    /// Name of the physical response (e.g. the bulk density, kg/m^3).
    pub response: String,
    /// The dimensional factor, a monomial of the inputs (e.g. rho_p).
    pub factor: Monomial,
    /// Name of the dimensionless quantity that is fitted instead (e.g. the solid fraction).
    pub fitted: String,
}

/// The similarity an experiment declares: its dimensionless groups and its scaled responses.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Similarity {
    /// Dimensionless groups that replace the inputs they absorb as fitting variables.
    pub groups: Vec<Group>,
    /// Responses fitted as dimensionless fractions of a known factor.
    pub scaled: Vec<ScaledResponse>,
    /// Groups the equations do not read whose range over the data still bounds the model: a
    /// box in the fitted groups can hold points no run came near (Ca_pp = C_pp K_p^(-2/3) high
    /// at the stiff end, where the runs' C_pp stopped lower), so `C_pp`'s own range is kept.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub support: Vec<Group>,
}

impl Similarity {
    /// The similarity without the groups whose every input `is_fixed`: such a group is one
    /// number over the whole campaign, a constant rather than a fitting variable, and a range of
    /// one point outside which every prediction would be refused. Its inputs stop being absorbed.
    pub fn without_constant_groups(mut self, is_fixed: impl Fn(&str) -> bool) -> Similarity {
        self.groups
            .retain(|g| !g.monomial.powers.iter().all(|(n, _)| is_fixed(n)));
        self.support
            .retain(|g| !g.monomial.powers.iter().all(|(n, _)| is_fixed(n)));
        self
    }

    /// The similarity with the groups `names` moved to the support: the equations no longer read
    /// them, but their range over the runs still bounds the model. A correction fitted this way
    /// reads the stiffness only through the cohesion's contact pull (`Ca_pp = C_pp K_p^(-2/3)`)
    /// when `K_p` and `K_w` are left unread, so beyond the stiffness of its cohesive runs it
    /// carries the similarity the DEM measured (docs/cohesion_stiffness.md) instead of a trend in
    /// K_p that no cohesive run constrains. Refuses a name that is no fitted group.
    pub fn with_unread(mut self, names: &[String]) -> std::result::Result<Similarity, String> {
        for name in names {
            let g = take_group(&mut self.groups, name, "the groups the equations read")?;
            self.support.push(g);
        }
        Ok(self)
    }

    /// The similarity without the support groups `names`: their range over the runs no longer
    /// bounds the model. With the stiffness left unread ([`Similarity::with_unread`]) a
    /// cohesion's reach at a stiffness is its contact pull's range (Ca), which the DEM keeps
    /// from K 1.94e5 to 1e7 at fixed Ca (docs/cohesion_stiffness.md), not the C range the runs
    /// held at their own stiffness. Refuses a name that is no support group.
    pub fn without_support(mut self, names: &[String]) -> std::result::Result<Similarity, String> {
        for name in names {
            take_group(&mut self.support, name, "the support groups")?;
        }
        Ok(self)
    }

    /// Every input the similarity reads: those its groups absorb and those its scaled responses'
    /// factors are made of (a fixed one must still be an input, or the factor has no value).
    pub fn needed_inputs(&self) -> Vec<String> {
        let mut v = self.absorbed();
        for s in &self.scaled {
            for (n, _) in &s.factor.powers {
                if !v.contains(n) {
                    v.push(n.clone());
                }
            }
        }
        v
    }

    /// Inputs that act only through the groups: the equations are fitted without them. A
    /// support group's inputs count: an input the equations may not read through its group
    /// ([`Similarity::with_unread`]) must not come back as a raw variable.
    pub fn absorbed(&self) -> Vec<String> {
        let mut v: Vec<String> = Vec::new();
        for g in self.groups.iter().chain(&self.support) {
            for (n, _) in &g.monomial.powers {
                if !v.contains(n) {
                    v.push(n.clone());
                }
            }
        }
        v
    }

    /// The scaling of `response`, if it is a scaled response.
    pub fn scaled(&self, response: &str) -> Option<&ScaledResponse> {
        self.scaled.iter().find(|s| s.response == response)
    }
}

/// Removes the group `name` from `list` (described as `what` in the refusal, which names the
/// groups there are).
fn take_group(list: &mut Vec<Group>, name: &str, what: &str) -> std::result::Result<Group, String> {
    match list.iter().position(|g| g.name == name) {
        Some(k) => Ok(list.remove(k)),
        None => Err(format!(
            "{name} is not one of {what} (they are: {})",
            list.iter()
                .map(|g| g.name.as_str())
                .collect::<Vec<_>>()
                .join(", ")
        )),
    }
}

/// `name / (rho_p g d50)` with d50 in mm: a stress per particle weight per area.
pub fn per_particle_weight(name: &str) -> Monomial {
    Monomial {
        // g in m/s^2, d50 in mm.
        coefficient: 1.0 / (9.81 * 1e-3),
        powers: vec![
            (name.into(), 1.0),
            ("rho_p".into(), -1.0),
            ("d50".into(), -1.0),
        ],
    }
}

/// The group of a cohesion energy density `name` (`ced_pp`; `pair` its suffix `_pp`): the
/// pull ced x contact area of a contact under a particle's weight, per that weight. Every normal
/// force of the classes is Hertz elasticity, whose contact area under a force F is (F R /
/// E*)^(2/3), so the pull per weight is C K^(-2/3) with C = ced / (rho_p g d50) and K the
/// contact's stiffness group: `Ca_pp = ced_pp E_p^(-2/3) (rho_p g d50)^(-1/3)`. A run keeps its
/// responses when ced and E change at fixed Ca (docs/cohesion_stiffness.md measures it over
/// three decades of K), which C alone does not: a model fitted in C has no reason to fade its
/// cohesion with stiffness, one fitted in Ca has it built in. The wall contact's modulus E* is
/// E_p E_w / (E_p + E_w) (one Poisson ratio); a monomial cannot hold it, so `Ca_pw` takes E_p,
/// its limit at a wall stiffer than the grains, and leaves E_w to K_w.
fn contact_pull(name: &str, pair: &str, what: &str) -> Group {
    let c = per_particle_weight(name);
    // A geometric mean sqrt(E_p E_w) in the wall's place was tried: it coupled the wall's
    // cohesion to K_w, and the retrained fit was not monotonic in ced_pw (docs/cohesion_stiffness.md).
    let powers = vec![
        (name.to_string(), 1.0),
        ("E_p".to_string(), -2.0 / 3.0),
        ("rho_p".to_string(), -1.0 / 3.0),
        ("d50".to_string(), -1.0 / 3.0),
    ];
    Group {
        name: format!("Ca{pair}"),
        what: format!(
            "{what}: its pull on a Hertz contact per particle weight, C{pair} K^(-2/3) = {name} \
             E*^(-2/3) (rho_p g d50)^(-1/3)"
        ),
        monomial: Monomial {
            // C K^(-2/3): the weight's coefficient to the power 1 - 2/3.
            coefficient: c.coefficient.cbrt(),
            powers,
        },
    }
}

/// The support groups ([`Similarity::support`]) of [`bulk_groups`]: for each cohesion energy
/// density of the class for `pairs`, C = ced / (rho_p g d50), whose range over the runs bounds
/// the model where its fitted group [`contact_pull`] alone would not.
pub fn bulk_support(
    class: &mbgc_dem::contact::ModelClass,
    pairs: &[mbgc_dem::contact::Pair],
) -> Vec<Group> {
    class
        .parameters(pairs)
        .iter()
        .filter_map(|(name, spec, _)| {
            let pair = name.strip_prefix("ced")?;
            Some(Group {
                name: format!("C{pair}"),
                what: format!(
                    "{} per particle weight per area, {name} / (rho_p g d50): a bound of the \
                     runs, not read by the equations",
                    spec.what
                ),
                monomial: per_particle_weight(name),
            })
        })
        .collect()
}

/// The groups of a bulk experiment under gravity whose only lengths are d50 and sizes in units
/// of it, and whose stresses are E_p, E_w (when the material meets walls: `pairs`), `stresses`
/// (the experiment's own, as (group name, parameter, meaning)) and any effect parameter of the
/// class for those pairs that is a stress (cohesion's energy density): K_p = E_p /
/// (rho_p g d50), K_w, the experiment's, then a cohesion's Ca_pp = C_pp K_p^(-2/3)
/// ([`contact_pull`]) and any other stress's Pi = stress / (rho_p g d50). `None` when the
/// class has an effect parameter of another dimension (a spring in N/m), which would need a group of its own.
pub fn bulk_groups(
    class: &mbgc_dem::contact::ModelClass,
    pairs: &[mbgc_dem::contact::Pair],
    stresses: &[(&str, &str, &str)],
) -> Option<Vec<Group>> {
    let params = class.parameters(pairs);
    let stress = |unit: &str| unit == "J/m^3" || unit == "Pa";
    if params
        .iter()
        .any(|(_, spec, _)| spec.unit != "-" && !stress(spec.unit))
    {
        return None;
    }
    let mut groups = vec![Group {
        name: "K_p".into(),
        what: "dimensionless particle stiffness E_p / (rho_p g d50)".into(),
        monomial: per_particle_weight("E_p"),
    }];
    if pairs.contains(&mbgc_dem::contact::Pair::ParticleWall) {
        groups.push(Group {
            name: "K_w".into(),
            what: "dimensionless wall stiffness E_w / (rho_p g d50)".into(),
            monomial: per_particle_weight("E_w"),
        });
    }
    for (group, name, what) in stresses {
        groups.push(Group {
            name: group.to_string(),
            what: format!("{what} per particle weight per area, {name} / (rho_p g d50)"),
            monomial: per_particle_weight(name),
        });
    }
    for (name, spec, _) in params.iter().filter(|(_, spec, _)| stress(spec.unit)) {
        groups.push(match name.strip_prefix("ced") {
            Some(pair) => contact_pull(name, pair, spec.what),
            None => Group {
                name: format!("Pi_{name}"),
                what: format!(
                    "{} per particle weight per area, {name} / (rho_p g d50)",
                    spec.what
                ),
                monomial: per_particle_weight(name),
            },
        });
    }
    Some(groups)
}

#[cfg(test)]
mod tests {
    use super::*;
    use mbgc_sr::eval::Evaluator;

    fn k() -> Monomial {
        Monomial {
            coefficient: 1.0 / 9.81e-3,
            powers: vec![("E".into(), 1.0), ("rho".into(), -1.0), ("d".into(), -1.0)],
        }
    }

    fn eval(prog: &[Node], x: &[f64]) -> f64 {
        let cols: Vec<Vec<f64>> = x.iter().map(|&v| vec![v]).collect();
        let mut out = [0.0];
        assert!(Evaluator::new().eval(prog, &cols, &mut out));
        out[0]
    }

    #[test]
    fn programs_compute_the_monomial_and_its_log() {
        let var = |n: &str| ["E", "rho", "d"].iter().position(|m| *m == n).unwrap() as u16;
        let x = [5e6, 2600.0, 8.0];
        let m = k();
        let want = 5e6 / (2600.0 * 9.81e-3 * 8.0);
        let got = m.value(|n| x[var(n) as usize]);
        assert!((got / want - 1.0).abs() < 1e-14, "{got} {want}");
        assert!((eval(&m.ln_program(&var), &x) - want.ln()).abs() < 1e-12);
        assert!((eval(&m.program(&var), &x) / want - 1.0).abs() < 1e-12);
        let rho = Monomial {
            coefficient: 1.0,
            powers: vec![("rho".into(), 1.0)],
        };
        assert_eq!(rho.program(&var), vec![Node::Var(1)]);
        let sq = Monomial {
            coefficient: 2.0,
            powers: vec![("d".into(), 2.0), ("E".into(), -0.5)],
        };
        let want = 2.0 * 64.0 / 5e6f64.sqrt();
        assert!((eval(&sq.program(&var), &x) / want - 1.0).abs() < 1e-12);
        assert!((m.log_derivative("rho", 2600.0) + 1.0 / 2600.0).abs() < 1e-18);
        assert_eq!(m.log_derivative("nu", 0.3), 0.0);
        assert_eq!(m.text(), "101.9 E / (rho d)");
        // A zero-able factor of power 1 with fractional others: the product is exact at zero,
        // and the zero never meets a logarithm (whose derivative there is infinite).
        let pull = Monomial {
            coefficient: 3.0,
            powers: vec![
                ("d".into(), 1.0),
                ("E".into(), -2.0 / 3.0),
                ("rho".into(), -1.0),
            ],
        };
        let p = pull.product_program(&var).unwrap();
        let want = 3.0 * 8.0 * 5e6f64.powf(-2.0 / 3.0) / 2600.0;
        assert!((eval(&p, &x) / want - 1.0).abs() < 1e-12);
        assert_eq!(eval(&p, &[5e6, 2600.0, 0.0]), 0.0);
        let logs_of_d = p
            .windows(2)
            .filter(|w| w[0] == Node::Var(2) && w[1] == Node::Log)
            .count();
        assert_eq!(logs_of_d, 0, "{p:?}");
        // Integer powers keep the plain product and quotient.
        assert_eq!(
            k().product_program(&var).unwrap(),
            vec![
                Node::Var(0),
                Node::Var(1),
                Node::Div,
                Node::Var(2),
                Node::Div,
                Node::Const(1.0 / 9.81e-3),
                Node::Mul
            ]
        );
    }
}
