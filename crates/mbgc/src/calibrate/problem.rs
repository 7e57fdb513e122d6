//! The calibration problem: a metamodel, the material's measurements, what is fixed, the search
//! box of the free parameters and the constraints between them.

use super::objective::Objective;
use crate::error::{Error, Result};
use crate::material::{Constraint, Material};
use crate::metamodel::Metamodel;
use mbgc_dem::contact::Pair;

/// A measured response the fit must match.
#[derive(Clone, Debug)]
pub struct Target {
    /// Index of the response in the model's `responses`.
    pub response: usize,
    /// The response's name.
    pub name: String,
    /// The measured value, in the response's unit.
    pub value: f64,
    /// Standard deviation of the measurement (same unit, > 0): the residual's scale in chi^2.
    pub sd: f64,
}

/// The inversion of a metamodel for one material: minimise chi^2 = sum ((g_i(x) - y_i) / sd_i)^2
/// over the free parameters in their box, the fixed ones (material values, PSD) held. The box is
/// physical; the optimiser's starts and the flat directions live on the unit cube that
/// [`Problem::from_unit`] maps onto it.
#[derive(Clone, Debug)]
pub struct Problem<'m> {
    /// The metamodel being inverted.
    pub model: &'m Metamodel,
    /// Every model input name, in model order.
    pub names: Vec<String>,
    /// A full input vector in model order: fixed entries hold their value, free ones the middle
    /// of their range (overwritten by [`Problem::full`]).
    pub base: Vec<f64>,
    /// Indices (into `names`) of the searched parameters.
    pub free: Vec<usize>,
    /// Lower bound of each free parameter (physical units): the material's `[bounds]`, else the
    /// model's domain.
    pub lower: Vec<f64>,
    /// Upper bound of each free parameter, as `lower`.
    pub upper: Vec<f64>,
    /// The measured responses the model must match.
    pub targets: Vec<Target>,
    /// The material's linear constraints, each with its terms as `(index into names,
    /// coefficient)`; `sum + constant <= 0` must hold.
    pub constraints: Vec<(Constraint, Vec<(usize, f64)>)>,
    /// What was decided on the user's behalf (PSD fitted, parameters left free, ...).
    pub notes: Vec<String>,
}

/// Whether a value given in a file is the constant a model was trained at (to rounding).
pub fn same_value(constant: f64, given: f64) -> bool {
    (constant - given).abs() <= 1e-9 * constant.abs().max(given.abs())
}

/// Penalty weight of a constraint violation (in parameter units, squared).
const PENALTY: f64 = 1e6;

/// Refuses a material that needs an effect the metamodel was not trained with (by its `[model]
/// class` or by a fixed or bounded parameter of that effect), naming the effect.
fn check_class(model: &Metamodel, material: &Material) -> Result<()> {
    let file = material.source.as_str();
    let Some(theirs) = model.class()? else {
        if let Some(mine) = material.model_class {
            return Err(Error::input(
                file,
                "model.class",
                format!(
                    "{mine}, but the metamodel records no model class (fitted on a table \
                     without one): nothing confirms it describes these effects; refit with \
                     --model-class, or remove [model] from the material"
                ),
            ));
        }
        return Ok(());
    };
    if let Some(mine) = material.model_class {
        let lacking = mine.missing_from(&theirs);
        let extra = theirs.missing_from(&mine);
        if !lacking.is_empty() {
            return Err(Error::input(
                file,
                "model.class",
                format!(
                    "{mine} needs {}, which the metamodel (trained on {theirs}) lacks: fit one on \
                     a campaign run with --model-class {mine}",
                    lacking.join(", ")
                ),
            ));
        }
        if !extra.is_empty() {
            return Err(Error::input(
                file,
                "model.class",
                format!(
                    "{mine}, but the metamodel has {theirs} (also {}): calibrating would give \
                     values to effects the material says it lacks; expected the metamodel's \
                     class or a metamodel of {mine}",
                    extra.join(", ")
                ),
            ));
        }
    }
    let names = material
        .fixed
        .iter()
        .map(|(n, _)| ("fixed", n))
        .chain(material.bounds.iter().map(|(n, _)| ("bounds", n)));
    for (table, name) in names {
        theirs
            .refuse_inactive(name, &Pair::BOTH, "the metamodel")
            .map_err(|e| {
                Error::input(
                    file,
                    format!("{table}.{name}"),
                    format!("{e} (the metamodel was trained on {theirs})"),
                )
            })?;
    }
    Ok(())
}

impl<'m> Problem<'m> {
    /// The problem of `material` against `model`. Refuses, among others, a measured response the
    /// model lacks, a model class that does not match, and fixed values, PSD parameters or bounds
    /// outside the model's domain (an [`Error::OutOfDomain`]: the equations would extrapolate).
    pub fn new(model: &'m Metamodel, material: &Material) -> Result<Problem<'m>> {
        let file = material.source.as_str();
        check_class(model, material)?;
        let names = model.input_names();
        let mut targets = Vec::new();
        for m in &material.measured {
            let idx = model
                .responses
                .iter()
                .position(|r| r.name == m.response)
                .ok_or_else(|| {
                    let known: Vec<&str> =
                        model.responses.iter().map(|r| r.name.as_str()).collect();
                    Error::input(
                        file,
                        format!("measured.{}", m.response),
                        format!(
                            "not a response of the model; expected one of: {}",
                            known.join(", ")
                        ),
                    )
                })?;
            targets.push(Target {
                response: idx,
                name: m.response.clone(),
                value: m.value,
                sd: m.sd,
            });
        }
        let mut fixed: Vec<Option<f64>> = vec![None; names.len()];
        let mut notes = Vec::new();
        let index = |name: &str, field: String| {
            names.iter().position(|n| n == name).ok_or_else(|| {
                Error::input(
                    file,
                    field,
                    format!(
                        "not a parameter of the model; expected one of: {}",
                        names.join(", ")
                    ),
                )
            })
        };
        let in_domain = |k: usize, v: f64, field: String| -> Result<()> {
            let d = model.inputs[k].domain;
            if v >= d[0] && v <= d[1] {
                Ok(())
            } else {
                Err(Error::out_of_domain(
                    file,
                    field,
                    format!(
                        "a value inside the model's valid domain [{}, {}] (got {v}; outside it \
                         the equations extrapolate)",
                        d[0], d[1]
                    ),
                ))
            }
        };
        for (name, v) in &material.fixed {
            if let Some(c) = model.constants.iter().find(|c| c.name == *name) {
                if !same_value(c.value, *v) {
                    return Err(Error::out_of_domain(
                        file,
                        format!("fixed.{name}"),
                        format!(
                            "{}, the value the metamodel's campaign held it at (got {v}): the \
                             model describes no other",
                            c.value
                        ),
                    ));
                }
                continue;
            }
            let k = index(name, format!("fixed.{name}"))?;
            in_domain(k, *v, format!("fixed.{name}"))?;
            fixed[k] = Some(*v);
        }
        if let Some((d50, sigma)) = material.psd_parameters()? {
            for (name, v) in [("d50", d50), ("sigma_ln", sigma)] {
                if let Some(k) = names.iter().position(|n| n == name) {
                    if fixed[k].is_some() {
                        return Err(Error::input(
                            file,
                            format!("fixed.{name}"),
                            format!("{name} to come from [psd] or [fixed], not both"),
                        ));
                    }
                    in_domain(k, v, format!("psd ({name} = {v:.4})"))?;
                    fixed[k] = Some(v);
                    notes.push(format!("{name} = {v:.4} from the PSD"));
                } else if let Some(c) = model.constants.iter().find(|c| c.name == name) {
                    if !same_value(c.value, v) {
                        return Err(Error::out_of_domain(
                            file,
                            format!("psd ({name} = {v:.4})"),
                            format!(
                                "{}, the value the metamodel's campaign held {name} at: the \
                                 model describes no other",
                                c.value
                            ),
                        ));
                    }
                } else if name == "sigma_ln" && v != 0.0 {
                    // Dropping it would calibrate a graded material on monosized runs.
                    return Err(Error::input(
                        file,
                        format!("psd (sigma_ln = {v:.4})"),
                        "a model that knows the size spread: this metamodel has no sigma_ln \
                         (its runs used the experiment's default, monosized spheres)"
                            .to_string(),
                    ));
                }
            }
        }
        // A group whose inputs are all fixed must lie in its domain already; one with free
        // inputs must be able to reach it from their domains (or no start has a prediction).
        for gd in &model.groups {
            let parts = &gd.group.monomial.powers;
            let values: Option<Vec<f64>> = parts
                .iter()
                .map(|(n, _)| names.iter().position(|m| m == n).and_then(|k| fixed[k]))
                .collect();
            if values.is_none() {
                let range = model.group_range(gd);
                let (mut lo, mut hi) =
                    (gd.group.monomial.coefficient, gd.group.monomial.coefficient);
                for (n, p) in parts {
                    let Some(k) = names.iter().position(|m| m == n) else {
                        continue;
                    };
                    let [a, b] = fixed[k].map_or(model.inputs[k].domain, |v| [v, v]);
                    let (a, b) = (a.powf(*p), b.powf(*p));
                    lo *= a.min(b);
                    hi *= a.max(b);
                }
                if hi < range[0] || lo > range[1] {
                    return Err(Error::out_of_domain(
                        file,
                        "fixed",
                        format!(
                            "{} = {} can only lie in [{lo:.4e}, {hi:.4e}] with the fixed values \
                             and the free ones in their domains, which misses the model's range \
                             [{:.4e}, {:.4e}] ({}): expected fixed values that let it inside; \
                             for this material, build a local model (`mbgc diagnose --build`)",
                            gd.group.name,
                            gd.group.monomial.text(),
                            range[0],
                            range[1],
                            gd.group.what
                        ),
                    ));
                }
            }
            if let Some(values) = values {
                let own = gd
                    .group
                    .monomial
                    .value(|n| values[parts.iter().position(|(m, _)| m == n).unwrap_or(0)]);
                // A cohesion group beyond the stiffness edge is read at its carried value,
                // which the contact's moduli decide too: known when they are fixed, else the
                // search keeps it inside.
                let carried = model.rigid_limit.as_ref().and_then(|l| {
                    let c = l.cohesion.iter().find(|c| c.group == gd.group.name)?;
                    let mut point: Vec<f64> = model
                        .inputs
                        .iter()
                        .map(|i| 0.5 * (i.domain[0] + i.domain[1]))
                        .collect();
                    for (k, f) in fixed.iter().enumerate() {
                        if let Some(v) = f {
                            point[k] = *v;
                        }
                    }
                    let known = |n: &str| {
                        names
                            .iter()
                            .position(|m| m == n)
                            .is_some_and(|k| fixed[k].is_some())
                    };
                    let stiffness: Vec<&str> = std::iter::once(l.along.as_str())
                        .chain(l.wall.as_ref().map(|(_, a)| a.as_str()))
                        .chain(c.contact.iter().map(String::as_str))
                        .collect();
                    Some(
                        stiffness
                            .iter()
                            .all(|n| known(n))
                            .then(|| model.group_read_value(&gd.group, &point)),
                    )
                });
                let v = match carried {
                    Some(Some(v)) => v,
                    Some(None) => continue,
                    None => own,
                };
                if v != own {
                    notes.push(format!(
                        "{} = {own:.4e} is read at the stiffness edge as {v:.4e}: beyond the \
                         training runs' stiffness a cohesive contact pulls as one on the edge \
                         with the cohesion times (E*_edge / E*)^(2/3), E* the contact's \
                         modulus (docs/cohesion_stiffness.md); the similarity's measured \
                         scatter is added to each response's sd",
                        gd.group.name
                    ));
                }
                let range = model.group_range(gd);
                if !(v >= range[0] && v <= range[1]) {
                    return Err(Error::out_of_domain(
                        file,
                        "fixed",
                        format!(
                            "{} = {} = {v:.4e} from the fixed {} is not inside the model's \
                             range [{:.4e}, {:.4e}] ({}; outside it the equations \
                             extrapolate): expected fixed values that put it inside; for this \
                             material, build a local model (`mbgc diagnose --build`)",
                            gd.group.name,
                            gd.group.monomial.text(),
                            parts
                                .iter()
                                .map(|(n, _)| n.as_str())
                                .collect::<Vec<_>>()
                                .join(", "),
                            range[0],
                            range[1],
                            gd.group.what
                        ),
                    ));
                }
                if !(v >= gd.domain[0] && v <= gd.domain[1]) {
                    let edge = if v > gd.domain[1] {
                        gd.domain[1]
                    } else {
                        gd.domain[0]
                    };
                    notes.push(format!(
                        "{} = {v:.4e} lies {:.2} decades beyond the training runs' {} \
                         {edge:.4e}: the model answers by its rigid limit (the equations at \
                         {edge:.4e} plus the shift measured along lines of DEM runs, whose \
                         scatter is added to each response's sd)",
                        gd.group.name,
                        (v / edge).log10().abs(),
                        if v > edge { "stiffest" } else { "softest" },
                    ));
                }
            }
        }
        for c in &model.constants {
            if !material.fixed.iter().any(|(n, _)| *n == c.name) {
                notes.push(format!(
                    "{} = {} as the metamodel's campaign held it",
                    c.name, c.value
                ));
            }
        }
        if !model.groups.is_empty() {
            notes.push(format!(
                "the model is fitted in {}: each kept inside the range it answers in (its \
                 training data's, or its rigid limit's reach)",
                model
                    .groups
                    .iter()
                    .map(|g| {
                        let r = model.group_range(g);
                        format!(
                            "{} = {} in [{:.3e}, {:.3e}]",
                            g.group.name,
                            g.group.monomial.text(),
                            r[0],
                            r[1]
                        )
                    })
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        if !model.constraints.is_empty() {
            notes.push(format!(
                "the model holds where its training runs were, inside {}: kept there",
                model.constraints.join(", ")
            ));
        }
        let mut lower: Vec<f64> = model.inputs.iter().map(|i| i.domain[0]).collect();
        let mut upper: Vec<f64> = model.inputs.iter().map(|i| i.domain[1]).collect();
        for (name, [lo, hi]) in &material.bounds {
            let k = index(name, format!("bounds.{name}"))?;
            if fixed[k].is_some() {
                return Err(Error::input(
                    file,
                    format!("bounds.{name}"),
                    format!("{name} is fixed (by [fixed] or [psd]); a range makes no sense"),
                ));
            }
            let d = model.inputs[k].domain;
            if *lo < d[0] || *hi > d[1] {
                return Err(Error::out_of_domain(
                    file,
                    format!("bounds.{name}"),
                    format!("a range inside the model's domain [{}, {}]", d[0], d[1]),
                ));
            }
            lower[k] = *lo;
            upper[k] = *hi;
        }
        let free: Vec<usize> = (0..names.len()).filter(|&k| fixed[k].is_none()).collect();
        for &k in &free {
            if !material.bounds.iter().any(|(n, _)| *n == names[k]) {
                notes.push(format!(
                    "{} searched over the model's domain [{}, {}]",
                    names[k], lower[k], upper[k]
                ));
            }
        }
        let mut constraints = Vec::new();
        for (i, c) in material.constraints.iter().enumerate() {
            let mut terms = Vec::new();
            for (n, coef) in &c.terms {
                terms.push((index(n, format!("constraints.expr[{i}]"))?, *coef));
            }
            constraints.push((c.clone(), terms));
        }
        let base: Vec<f64> = fixed
            .iter()
            .zip(lower.iter().zip(&upper))
            .map(|(f, (lo, hi))| f.unwrap_or(0.5 * (lo + hi)))
            .collect();
        Ok(Problem {
            model,
            lower: free.iter().map(|&k| lower[k]).collect(),
            upper: free.iter().map(|&k| upper[k]).collect(),
            names,
            base,
            free,
            targets,
            constraints,
            notes,
        })
    }

    /// Number of free parameters.
    pub fn dim(&self) -> usize {
        self.free.len()
    }

    /// Names of the free parameters, in search order.
    pub fn free_names(&self) -> Vec<&str> {
        self.free.iter().map(|&k| self.names[k].as_str()).collect()
    }

    /// All model inputs with the free ones set.
    pub fn full(&self, free: &[f64]) -> Vec<f64> {
        let mut x = self.base.clone();
        for (&k, &v) in self.free.iter().zip(free) {
            x[k] = v;
        }
        x
    }

    /// Physical free parameters from unit coordinates.
    pub fn from_unit(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .enumerate()
            .map(|(j, &u)| self.lower[j] + (self.upper[j] - self.lower[j]) * u)
            .collect()
    }

    /// The sd a target's residual is weighed with at `x` (all inputs): the measurement's, and
    /// beyond the model's data in the stiffness group the rigid limit's scatter (NaN past its
    /// reach).
    pub fn target_sd(&self, t: &Target, x: &[f64]) -> f64 {
        let extra = self
            .model
            .extrapolation_sd(&self.model.responses[t.response], x);
        t.sd.hypot(extra)
    }

    /// The sd of every target at the free parameters `free` (see [`Problem::target_sd`]).
    pub fn target_sds(&self, free: &[f64]) -> Vec<f64> {
        let x = self.full(free);
        self.targets.iter().map(|t| self.target_sd(t, &x)).collect()
    }

    /// Model predictions of the measured responses (NaN where an equation is not finite).
    pub fn predictions(&self, free: &[f64]) -> Vec<f64> {
        let x = self.full(free);
        self.targets
            .iter()
            .map(|t| {
                self.model
                    .predict_point(&self.model.responses[t.response], &x)
            })
            .collect()
    }

    /// Sum of squared violations of the constraints, and of the model's group domains (in
    /// natural-log units: a group 10 % beyond its range counts 0.0095).
    pub fn violation(&self, free: &[f64]) -> f64 {
        let x = self.full(free);
        let groups: f64 = (0..self.model.groups.len())
            .map(|g| self.group_excess(g, &x).powi(2))
            .sum();
        groups
            + self.model.constraint_excess(&x)
            + self
                .constraints
                .iter()
                .map(|(c, terms)| {
                    let v = terms.iter().map(|(k, a)| a * x[*k]).sum::<f64>() + c.constant;
                    v.max(0.0).powi(2)
                })
                .sum::<f64>()
    }

    /// The dimensionless groups outside the model's range at `free`: each group's name, its
    /// formula, its value there and the range of the training runs.
    pub fn groups_outside(&self, free: &[f64]) -> Vec<(String, String, f64, [f64; 2])> {
        let x = self.full(free);
        (0..self.model.groups.len())
            .filter(|&g| self.group_excess(g, &x) != 0.0)
            .map(|g| {
                let gd = &self.model.groups[g];
                (
                    gd.group.name.clone(),
                    gd.group.monomial.text(),
                    self.model.group_read_value(&gd.group, &x),
                    self.model.group_range(gd),
                )
            })
            .collect()
    }

    /// How far group `g` lies outside its domain at `x`, in ln units, signed: positive above the
    /// range, negative below, 0 inside.
    fn group_excess(&self, g: usize, x: &[f64]) -> f64 {
        let gd = &self.model.groups[g];
        let v = self.model.group_read_value(&gd.group, x).ln();
        let range = self.model.group_range(gd);
        let (lo, hi) = (range[0].ln(), range[1].ln());
        if v > hi {
            v - hi
        } else if v < lo {
            v - lo
        } else {
            0.0
        }
    }

    /// chi^2 = sum ((prediction - measured) / sd)^2 plus the constraint penalty, and its gradient
    /// with respect to the free parameters; `None` where an equation is not finite.
    pub fn objective(&self, free: &[f64]) -> Option<(f64, Vec<f64>)> {
        let x = self.full(free);
        let mut f = 0.0;
        let mut g = vec![0.0; self.free.len()];
        for t in &self.targets {
            let (y, dy) = self
                .model
                .value_and_gradient(&self.model.responses[t.response], &x)?;
            let sd = self.target_sd(t, &x);
            let r = (y - t.value) / sd;
            f += r * r;
            for (j, &k) in self.free.iter().enumerate() {
                g[j] += 2.0 * r * dy[k] / sd;
            }
            // Beyond the data in the rigid limit's group the sd varies with the parameters: the
            // Gaussian's normalisation 2 ln sd then enters -2 ln L, else a free parameter could
            // lower chi^2 by moving where the limit's scatter is large. Measured from the target's
            // own sd, so it is 0 (and the objective unchanged) inside the data.
            if sd > t.sd {
                f += 2.0 * (sd / t.sd).ln();
                for (j, &k) in self.free.iter().enumerate() {
                    let h = self.model.difference_step(k, x[k]);
                    let (mut lo, mut hi) = (x.clone(), x.clone());
                    lo[k] -= h;
                    hi[k] += h;
                    let dsd = (self.target_sd(t, &hi) - self.target_sd(t, &lo)) / (2.0 * h);
                    if dsd.is_finite() {
                        // d/dsd (r^2 + 2 ln sd) = (2 - 2 r^2) / sd.
                        g[j] += (2.0 - 2.0 * r * r) * dsd / sd;
                    }
                }
            }
        }
        // A group outside the range the model was fitted on is extrapolation, like an input
        // outside its bounds: kept out by a penalty on its log.
        for gi in 0..self.model.groups.len() {
            let v = self.group_excess(gi, &x);
            if v != 0.0 {
                f += PENALTY * v * v;
                let m = &self.model.groups[gi].group.monomial;
                for (j, &k) in self.free.iter().enumerate() {
                    g[j] += 2.0 * PENALTY * v * m.log_derivative(&self.names[k], x[k]);
                }
            }
        }
        // Where the model's training runs did not go (a limit of its space), as for a group.
        let (e, de) = self.model.constraint_excess_with_gradient(&x);
        if e > 0.0 {
            f += PENALTY * e;
            for (j, &k) in self.free.iter().enumerate() {
                g[j] += PENALTY * de[k];
            }
        }
        for (c, terms) in &self.constraints {
            let v = terms.iter().map(|(k, a)| a * x[*k]).sum::<f64>() + c.constant;
            if v > 0.0 {
                f += PENALTY * v * v;
                for (k, a) in terms {
                    if let Some(j) = self.free.iter().position(|f| f == k) {
                        g[j] += 2.0 * PENALTY * v * a;
                    }
                }
            }
        }
        Some((f, g))
    }

    /// 2 sum ln(sd / measured sd) over the targets: the part of the objective (-2 ln L up to a
    /// constant) that the rigid limit's scatter adds beyond the data; 0 inside.
    pub fn sd_term(&self, free: &[f64]) -> f64 {
        self.targets
            .iter()
            .zip(self.target_sds(free))
            .map(|(t, sd)| {
                if sd > t.sd {
                    2.0 * (sd / t.sd).ln()
                } else {
                    0.0
                }
            })
            .sum()
    }

    /// Normalised residuals `(prediction - measured) / sd`.
    pub fn residuals(&self, free: &[f64]) -> Vec<f64> {
        self.predictions(free)
            .iter()
            .zip(&self.targets)
            .zip(self.target_sds(free))
            .map(|((p, t), sd)| (p - t.value) / sd)
            .collect()
    }
}

impl Objective for Problem<'_> {
    fn lower(&self) -> &[f64] {
        &self.lower
    }
    fn upper(&self) -> &[f64] {
        &self.upper
    }
    fn objective(&self, x: &[f64]) -> Option<(f64, Vec<f64>)> {
        Problem::objective(self, x)
    }
}
