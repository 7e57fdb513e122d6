//! How a model answers for materials stiffer (or softer) than its campaign ran: the rigid limit.
//!
//! Without cohesion the shear box sees E_p, rho_p and d50 only through K_p = E_p / (rho_p g d50).
//! Seed 004's ranges put K_p between about 7e3 and 5e8, but a run's cost grows about as
//! sqrt(K_p) while the responses approach a rigid limit (docs/stiffness.md), so a campaign covers
//! a part of that range and the rest is answered here. Beyond the model's range in the group the
//! equation is evaluated at the range's edge (the input `along`, E_p, scaled so that the group
//! sits on the edge), and a measured curve adds what the response still does beyond it: a shift
//! and its standard deviation, both functions of how many decades the group lies beyond the edge.
//!
//! The curves come from lines of DEM runs that vary only the group through points of the space
//! (`mbgc bench stiffness`), and take one of two forms per response and side, whichever predicts
//! a left-out line better:
//! - `shift`: the same shift for every material (the mean over the lines);
//! - `slope`: the equation's own slope at the edge (per decade) times a measured length in
//!   decades, so a material whose response still moved at the edge moves on, one that had
//!   stopped stays.
//!
//! The standard deviation at a knot is the lines' scatter about the curve with the runs' own
//! noise taken off: how much the shift differs between materials. It is added to the model's
//! own error (which holds one run's noise) wherever the curve is used. Past the last measured
//! knot the model does not answer.
//!
//! A cohesive model's cohesion groups (C_pp = ced_pp / (rho_p g d50)) do not stay put beyond the
//! edge: SJKR pulls with ced times the contact area, and under gravity a Hertz contact's area
//! over d50^2 scales as K^(-2/3) (K the contact's stiffness group), so a material beyond the edge
//! acts as one on the edge with C (K_edge / K)^(2/3) (`docs/cohesion_stiffness.md` measures it in
//! the DEM). The equation is read there, and a measured scatter of that similarity, growing with
//! the mapped cohesion and the decades beyond the edge, is added to the error.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// How a curve's shift depends on the material.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Form {
    /// The same shift (in the fitted, dimensionless response) for every material.
    Shift,
    /// The equation's slope per decade at the edge times the knot's value (in decades).
    Slope,
}

/// A point of a curve: the group `decades` beyond the edge (negative: softer than the softest
/// data), the curve's value there and the scatter of the lines about it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Knot {
    /// log10(group / edge): positive beyond the largest value of the data, negative below the
    /// smallest.
    pub decades: f64,
    /// The shift (form `shift`, in the fitted response's unit) or the length in decades (form
    /// `slope`).
    pub value: f64,
    /// How far a material's shift may lie from the curve (in the fitted response's unit): the
    /// lines' scatter about it with the runs' own noise taken off (a prediction's error holds
    /// one run's noise already), plus the curve value's own uncertainty (scatter^2 / lines).
    pub sd: f64,
    /// The lines' scatter about the curve as measured, noise included.
    pub scatter: f64,
    /// Lines measured here.
    pub lines: usize,
}

/// One response's curve on one side of the data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    /// The response (a column of the model).
    pub response: String,
    /// `true`: beyond the largest value of the data; `false`: below the smallest.
    pub stiff: bool,
    /// The form chosen.
    pub form: Form,
    /// The knots away from the edge, ordered from it; the edge itself (shift 0, sd 0) is implied.
    pub knots: Vec<Knot>,
    /// Root mean square error of each form predicting a left-out line's shifts from the other
    /// lines (in the fitted response's unit; `None` where a form cannot be fitted): what chose
    /// the form.
    pub leave_one_out: LeaveOneOut,
}

/// Leave-one-line-out errors of the two forms.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LeaveOneOut {
    /// Of the `shift` form.
    pub shift: Option<f64>,
    /// Of the `slope` form.
    pub slope: Option<f64>,
}

/// The rigid-limit treatment of one group of a model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RigidLimit {
    /// The group the curves extend (`K_p`).
    pub group: String,
    /// The input moved along the group to clamp it to the edge (`E_p`: it enters no other group).
    pub along: String,
    /// The wall's group and input (`K_w`, `E_w`), clamped the same way: the lines move both
    /// together, so a wall beyond its range adds the curve's scatter at its excess (no shift).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub wall: Option<(String, String)>,
    /// The group's range where the model answers: the lines' softest and stiffest values.
    pub reach: [f64; 2],
    /// One curve per response and side measured.
    pub curves: Vec<Curve>,
    /// The lines the curves were measured on.
    pub lines: Vec<String>,
    /// The tables of runs they came from, with their FNV-1a 64 hashes.
    pub source: String,
    /// The cohesion groups read at the edge's equivalent cohesion (empty: a model without
    /// cohesion).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cohesion: Vec<Cohesion>,
}

/// The power of the contact stiffness by which a cohesion group is carried to the edge: a Hertz
/// overlap under a given load scales as E*^(-2/3), and SJKR's force is ced times the contact
/// area pi R* delta.
pub const COHESION_POWER: f64 = 2.0 / 3.0;

/// A cohesion group carried to the stiffness edge: at a point beyond it the group is read at
/// `C (E*_edge / E*)^COHESION_POWER`, with E* the contact's effective modulus
/// (1 / E* ~ 1 / E_a + 1 / E_b; the Poisson factors are the same on both sides and cancel).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cohesion {
    /// The group (`C_pp`).
    pub group: String,
    /// Its input that moves it alone (`ced_pp`).
    pub along: String,
    /// The moduli of the contact's two sides (`E_p`, `E_p`; `E_p`, `E_w` for the wall's).
    pub contact: [String; 2],
    /// The group's value on the edge at which the scatter was measured: the scatter at another
    /// value is scaled by the ratio (no cohesion, no scatter).
    pub reference: f64,
    /// One scatter curve per response.
    pub curves: Vec<CohesionCurve>,
    /// Where the curves come from (the lines and tables, or the group they were taken from when
    /// this one was not measured).
    pub measured: String,
    /// The stiffness group's value where the effect's own runs stop, when that lies below the
    /// model's edge: a correction that reads the stiffness only through the contact pull
    /// (`C K^(-2/3)`) answers beyond its runs inside the model's data by the similarity alone,
    /// so its scatter counts from here, inside the data as beyond it. `None`: from the edge.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub runs_edge: Option<f64>,
}

/// How far the cohesion effect beyond the edge may lie from the edge's at the same carried
/// cohesion, for one response.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CohesionCurve {
    /// The response.
    pub response: String,
    /// Knots away from the edge (decades of the contact's stiffness), ordered from it.
    pub knots: Vec<CohesionKnot>,
}

/// One stiffness at which the similarity was measured.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CohesionKnot {
    /// Decades of the contact stiffness beyond the edge.
    pub decades: f64,
    /// The scatter added to a prediction there at the reference cohesion (fitted unit): the
    /// lines' root mean square difference with the runs' noise taken off, plus its own
    /// uncertainty (rms^2 / lines).
    pub sd: f64,
    /// The lines' mean difference (fitted unit), kept for the record: no shift is applied,
    /// which the mean's standard error `se` decides.
    pub mean: f64,
    /// The standard error of `mean`.
    pub se: f64,
    /// Lines measured here.
    pub lines: usize,
}

impl CohesionCurve {
    /// The scatter `decades` beyond the edge at the reference cohesion: linear from 0 on the
    /// edge (where the carried cohesion is the material's own) through the knots, and beyond
    /// the last in proportion to the decades (a similarity measured over d decades is taken to
    /// err as much again over each further d).
    pub fn sd_at(&self, decades: f64) -> f64 {
        let d = decades.abs();
        let mut prev = (0.0, 0.0);
        for k in &self.knots {
            let kd = k.decades.abs();
            if d <= kd {
                let t = if kd > prev.0 {
                    (d - prev.0) / (kd - prev.0)
                } else {
                    1.0
                };
                return prev.1 + t * (k.sd - prev.1);
            }
            prev = (kd, k.sd);
        }
        if prev.0 > 0.0 {
            prev.1 * d / prev.0
        } else {
            0.0
        }
    }
}

/// One line of DEM runs through a point of the space, as the fit sees it: its value at the
/// edge, the equation's slope there, the response's scale factor, and its values beyond.
#[derive(Clone, Debug)]
pub struct LineShifts {
    /// The line's name (the point it goes through).
    pub label: String,
    /// The equation's slope at the edge, per decade of the group, divided by `factor`.
    pub slope: f64,
    /// `(decades beyond the edge, measured value minus the value at the edge, divided by the
    /// response's factor)`, with `decades` on one side only.
    pub shifts: Vec<(f64, f64)>,
    /// The variance each shift has from the runs' noise alone (one run's variance times
    /// 1 / runs at the edge + 1 / runs there), in the fitted unit squared; parallel to `shifts`.
    pub noise: Vec<f64>,
}

/// Decades are matched across lines to this precision (lines run at the same values of K).
const SAME_DECADE: f64 = 1e-6;

impl Curve {
    /// Fits one response's curve on one side from its lines' shifts. Knots are the values of
    /// the group at least two lines measured. `None`: no such value.
    pub fn fit(response: &str, stiff: bool, lines: &[LineShifts]) -> Option<Curve> {
        let mut xs: Vec<f64> = lines
            .iter()
            .flat_map(|l| l.shifts.iter().map(|s| s.0))
            .filter(|x| x.is_finite() && (*x > 0.0) == stiff && *x != 0.0)
            .collect();
        xs.sort_by(|a, b| a.abs().total_cmp(&b.abs()));
        xs.dedup_by(|a, b| (*a - *b).abs() < SAME_DECADE);
        let at = |l: &LineShifts, x: f64| {
            l.shifts
                .iter()
                .zip(&l.noise)
                .find(|(s, _)| (s.0 - x).abs() < SAME_DECADE && s.1.is_finite())
                .map(|(s, v)| (s.1, *v))
        };
        let mut fits: [Vec<Knot>; 2] = [Vec::new(), Vec::new()];
        let mut loo: [(f64, usize, bool); 2] = [(0.0, 0, true), (0.0, 0, true)];
        for &x in &xs {
            let with_noise: Vec<(f64, f64, f64)> = lines
                .iter()
                .filter_map(|l| at(l, x).map(|(d, v)| (l.slope, d, v)))
                .collect();
            if with_noise.len() < 2 {
                continue;
            }
            let here: Vec<(f64, f64)> = with_noise.iter().map(|p| (p.0, p.1)).collect();
            let noise = with_noise.iter().map(|p| p.2).sum::<f64>() / here.len() as f64;
            for (k, form) in [Form::Shift, Form::Slope].into_iter().enumerate() {
                let Some((value, scatter)) = knot(form, &here) else {
                    loo[k].2 = false;
                    continue;
                };
                // How far a new material's shift lies from the curve: the lines' spread less
                // the runs' noise, plus the uncertainty of the curve's value from n lines.
                let n = here.len() as f64;
                let sd2 = (scatter * scatter - noise).max(0.0) + scatter * scatter / n;
                fits[k].push(Knot {
                    decades: x,
                    value,
                    sd: sd2.sqrt(),
                    scatter,
                    lines: here.len(),
                });
                for i in 0..here.len() {
                    let rest: Vec<(f64, f64)> = here
                        .iter()
                        .enumerate()
                        .filter(|(j, _)| *j != i)
                        .map(|(_, p)| *p)
                        .collect();
                    match knot(form, &rest) {
                        Some((v, _)) => {
                            let pred = predict(form, v, here[i].0);
                            loo[k].0 += (here[i].1 - pred).powi(2);
                            loo[k].1 += 1;
                        }
                        None => loo[k].2 = false,
                    }
                }
            }
        }
        let rmse = |(s, n, ok): (f64, usize, bool)| (ok && n > 0).then(|| (s / n as f64).sqrt());
        let leave_one_out = LeaveOneOut {
            shift: rmse(loo[0]),
            slope: rmse(loo[1]),
        };
        let slope_wins = matches!(
            (leave_one_out.shift, leave_one_out.slope),
            (Some(a), Some(b)) if b < a
        ) || (leave_one_out.shift.is_none() && leave_one_out.slope.is_some());
        let (form, knots) = if slope_wins {
            (Form::Slope, std::mem::take(&mut fits[1]))
        } else {
            (Form::Shift, std::mem::take(&mut fits[0]))
        };
        (!knots.is_empty()).then(|| Curve {
            response: response.to_string(),
            stiff,
            form,
            knots,
            leave_one_out,
        })
    }

    /// The curve's value and scatter `decades` beyond the edge, linear between the knots from
    /// the edge (0, 0); `None` past the last knot.
    pub fn at(&self, decades: f64) -> Option<(f64, f64)> {
        let d = decades.abs();
        let mut prev = (0.0, 0.0, 0.0);
        for k in &self.knots {
            let kd = k.decades.abs();
            if d <= kd + SAME_DECADE {
                let t = if kd > prev.0 {
                    ((d - prev.0) / (kd - prev.0)).clamp(0.0, 1.0)
                } else {
                    1.0
                };
                return Some((
                    prev.1 + t * (k.value - prev.1),
                    prev.2 + t * (k.sd - prev.2),
                ));
            }
            prev = (kd, k.value, k.sd);
        }
        None
    }
}

/// A knot's value and scatter from `(slope, shift)` pairs of its lines; `None` when the form
/// cannot be fitted (the slope form with every slope 0).
fn knot(form: Form, pairs: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = pairs.len() as f64;
    let value = match form {
        Form::Shift => pairs.iter().map(|p| p.1).sum::<f64>() / n,
        Form::Slope => {
            let ss: f64 = pairs.iter().map(|p| p.0 * p.0).sum();
            if ss <= 0.0 || !ss.is_finite() {
                return None;
            }
            pairs.iter().map(|p| p.0 * p.1).sum::<f64>() / ss
        }
    };
    let ss: f64 = pairs
        .iter()
        .map(|&(s, d)| (d - predict(form, value, s)).powi(2))
        .sum();
    let sd = if pairs.len() > 1 {
        (ss / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    Some((value, sd))
}

fn predict(form: Form, value: f64, slope: f64) -> f64 {
    match form {
        Form::Shift => value,
        Form::Slope => slope * value,
    }
}

/// Where a point lies along the limited group.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Place {
    /// log10(group / nearest edge) of the particle group (0 inside the data's range).
    pub decades: f64,
    /// The same for the wall group (0 inside, or without one).
    pub wall_decades: f64,
}

impl Place {
    /// Inside the data's range in both groups: the equation answers alone.
    pub fn inside(&self) -> bool {
        self.decades == 0.0 && self.wall_decades == 0.0
    }
}

/// Signed decades of `value` beyond `domain` (0 inside).
pub fn decades_beyond(value: f64, domain: [f64; 2]) -> f64 {
    if value > domain[1] {
        (value / domain[1]).log10()
    } else if value < domain[0] {
        (value / domain[0]).log10()
    } else {
        0.0
    }
}

impl RigidLimit {
    /// The curve of `response` on the side of `decades`.
    pub fn curve(&self, response: &str, decades: f64) -> Option<&Curve> {
        self.curves
            .iter()
            .find(|c| c.response == response && c.stiff == (decades > 0.0))
    }

    /// The shift (in the fitted response's unit; the caller multiplies a `slope` curve's value
    /// by the equation's slope) and the scatter for `response` at `place`. `None` where a
    /// curve is needed and there is none, or the place is past its last knot.
    pub fn shift(&self, response: &str, place: Place) -> Option<(f64, Form, f64)> {
        let (mut value, mut form, mut sd) = (0.0, Form::Shift, 0.0);
        if place.decades != 0.0 {
            let c = self.curve(response, place.decades)?;
            let (v, s) = c.at(place.decades)?;
            (value, form, sd) = (v, c.form, s);
        }
        if place.wall_decades != 0.0 && place.wall_decades.abs() > place.decades.abs() {
            let c = self.curve(response, place.wall_decades)?;
            let (_, s) = c.at(place.wall_decades)?;
            sd = sd.max(s);
        }
        Some((value, form, sd))
    }

    /// Checks a limit read from a model file: finite ascending knots, a reach around nothing
    /// impossible.
    pub fn validate(&self, file: &str) -> Result<()> {
        let bad = |field: String, what: &str| Err(Error::input(file, field, what.to_string()));
        for (i, c) in self.cohesion.iter().enumerate() {
            if !(c.reference.is_finite() && c.reference > 0.0) {
                return bad(
                    format!("rigid_limit.cohesion[{i}].reference"),
                    "a positive value of the group",
                );
            }
            if let Some(e) = c.runs_edge {
                if !(e.is_finite() && e > 0.0) {
                    return bad(
                        format!("rigid_limit.cohesion[{i}].runs_edge"),
                        "a positive value of the stiffness group",
                    );
                }
            }
            for (j, cc) in c.curves.iter().enumerate() {
                let mut last = 0.0;
                for (k, kn) in cc.knots.iter().enumerate() {
                    if !(kn.sd.is_finite() && kn.sd >= 0.0 && kn.decades.is_finite())
                        || kn.decades.abs() <= last
                    {
                        return bad(
                            format!("rigid_limit.cohesion[{i}].curves[{j}].knots[{k}]"),
                            "a finite sd of at least 0 at decades moving away from the edge",
                        );
                    }
                    last = kn.decades.abs();
                }
            }
        }
        if !(self.reach[0] > 0.0 && self.reach[0] <= self.reach[1] && self.reach[1].is_finite()) {
            return bad(
                "rigid_limit.reach".into(),
                "a positive range [min, max] of the group",
            );
        }
        for (i, c) in self.curves.iter().enumerate() {
            let mut last = 0.0;
            for (j, k) in c.knots.iter().enumerate() {
                let field = format!("rigid_limit.curves[{i}].knots[{j}]");
                if !(k.value.is_finite()
                    && k.sd.is_finite()
                    && k.sd >= 0.0
                    && k.scatter >= 0.0
                    && k.decades.is_finite())
                {
                    return bad(field, "a finite value and a sd of at least 0");
                }
                if (k.decades > 0.0) != c.stiff || k.decades.abs() <= last {
                    return bad(
                        field,
                        "decades on the curve's side of the edge, moving away from it",
                    );
                }
                last = k.decades.abs();
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(label: &str, slope: f64, shifts: &[(f64, f64)]) -> LineShifts {
        LineShifts {
            label: label.into(),
            slope,
            shifts: shifts.to_vec(),
            noise: vec![0.0; shifts.len()],
        }
    }

    #[test]
    fn a_shift_proportional_to_the_edge_slope_is_fitted_by_the_slope_form() {
        // Each line moves on by 0.8 decades of its own edge slope.
        let lines: Vec<LineShifts> = [-10.0, -20.0, -40.0, -5.0]
            .iter()
            .enumerate()
            .map(|(i, &s)| line(&format!("l{i}"), s, &[(0.7, 0.5 * s), (1.7, 0.8 * s)]))
            .collect();
        let c = Curve::fit("rho", true, &lines).unwrap();
        assert_eq!(c.form, Form::Slope);
        assert_eq!(c.knots.len(), 2);
        assert!((c.knots[1].value - 0.8).abs() < 1e-12);
        assert!(c.knots[1].sd < 1e-12);
        let (v, sd) = c.at(1.2).unwrap();
        assert!((v - 0.65).abs() < 1e-12, "halfway between the knots: {v}");
        assert!(sd < 1e-12);
        assert!(c.at(1.8).is_none(), "past the last knot");
        // The same shifts for every line: the shift form wins.
        let flat: Vec<LineShifts> = [-10.0, -20.0, -40.0]
            .iter()
            .map(|&s| line("f", s, &[(0.7, -3.0)]))
            .collect();
        let c = Curve::fit("rho", true, &flat).unwrap();
        assert_eq!(c.form, Form::Shift);
        assert_eq!(c.knots[0].value, -3.0);
    }

    #[test]
    fn the_scatter_is_the_lines_spread_and_a_zero_slope_leaves_the_shift_form() {
        let lines = [
            line("a", 0.0, &[(1.0, 1.0), (-0.2, 5.0)]),
            line("b", 0.0, &[(1.0, 3.0)]),
        ];
        let c = Curve::fit("angle", true, &lines).unwrap();
        assert_eq!(c.form, Form::Shift);
        assert_eq!(c.leave_one_out.slope, None);
        assert_eq!(c.knots[0].value, 2.0);
        assert!((c.knots[0].scatter - 2f64.sqrt()).abs() < 1e-12);
        assert!((c.knots[0].sd - 3f64.sqrt()).abs() < 1e-12);
        // The runs' noise is taken off the scatter: a variance of 1.5 of the 2 measured.
        let noisy: Vec<LineShifts> = lines
            .iter()
            .map(|l| LineShifts {
                noise: vec![1.5; l.shifts.len()],
                ..l.clone()
            })
            .collect();
        let c = Curve::fit("angle", true, &noisy).unwrap();
        // 2 - 1.5 of spread and 2 / 2 of the mean's uncertainty.
        assert!((c.knots[0].sd - 1.5f64.sqrt()).abs() < 1e-12);
        assert!((c.knots[0].scatter - 2f64.sqrt()).abs() < 1e-12);
        // Only one line below the edge: no soft curve.
        assert!(Curve::fit("angle", false, &lines).is_none());
    }

    #[test]
    fn a_wall_beyond_the_particles_adds_scatter_but_no_shift() {
        let c = Curve {
            response: "r".into(),
            stiff: true,
            form: Form::Shift,
            knots: vec![Knot {
                decades: 2.0,
                value: -10.0,
                sd: 4.0,
                scatter: 5.0,
                lines: 3,
            }],
            leave_one_out: LeaveOneOut {
                shift: Some(1.0),
                slope: None,
            },
        };
        let lim = RigidLimit {
            group: "K_p".into(),
            along: "E_p".into(),
            wall: Some(("K_w".into(), "E_w".into())),
            reach: [1.0, 100.0],
            curves: vec![c],
            lines: vec![],
            source: String::new(),
            cohesion: vec![],
        };
        let only_wall = Place {
            decades: 0.0,
            wall_decades: 1.0,
        };
        assert_eq!(lim.shift("r", only_wall), Some((0.0, Form::Shift, 2.0)));
        let both = Place {
            decades: 1.0,
            wall_decades: 0.5,
        };
        assert_eq!(lim.shift("r", both), Some((-5.0, Form::Shift, 2.0)));
        let soft = Place {
            decades: -0.1,
            wall_decades: 0.0,
        };
        assert_eq!(lim.shift("r", soft), None, "no soft curve");
        assert_eq!(decades_beyond(1000.0, [1.0, 100.0]), 1.0);
        assert_eq!(decades_beyond(50.0, [1.0, 100.0]), 0.0);
        assert!(lim.validate("m.json").is_ok());
    }
}
