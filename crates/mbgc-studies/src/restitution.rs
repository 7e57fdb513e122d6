//! Seed 003's restitution study (Hadjidoukas et al. 2014, Sec. 4, Tables 1-4) run directly on DEM
//! impacts: the wall-impact experiment is calibrated by TMCMC to the measured normal and
//! tangential restitution of a steel ball on a steel wall (Table 2) for the three normal-force
//! classes of Table 1, and the classes are ranked by their evidence.
//!
//! - Model classes: `F_n = k_n d^(3/2) + gamma_n d^alpha_n d'` with Hertz's
//!   `k_n = 4/3 Y* sqrt(R*)`, `alpha_n` = 1/4 (M1, Tsuji), 1/2 (M2, Kuwabara-Kono) or free (M3).
//!   Tangential: a constant spring `k_t` with a Coulomb cap `mu F_n` (the wall-impact
//!   experiment with the `linear-spring` effect, `k_t_pw`), no tangential dashpot (no restitution).
//!   The sampled `k_t` is in units of [`Setup::k_t_unit`] (1e7 N/m at the printed modulus,
//!   scaled with the contact time so that both moduli see the same range of tangential period
//!   over contact time); seed 003 does not print its unit.
//! - Parameters, in the paper's order: `(mu, [alpha_n,] gamma_n, k_t, sigma1_sq, sigma2_sq)`, all
//!   with uniform priors ([`Priors`]).
//! - Prediction error (the paper's Eqs. 4-8 and Sec. 4): `measured_r = g_r(theta) + e_r`,
//!   `e_r ~ N(0, sd_r^2 + s_g measured_r^2)` with `s_g = sigma1_sq` for the cnr group and
//!   `sigma2_sq` for the ctr group. The model-error variance scales with the *measured* value
//!   (the paper's `Sigma_m = sigma^2 diag(y_hat^2)`), not with the prediction as in
//!   [`mbgc::calibrate::bayes`], and the sampled parameters are the variances `sigma^2` themselves (Table 4
//!   prints `sigma1 = 0.0045` where the text says the error is 6.7 % = sqrt(0.0045)).
//! - Each likelihood evaluation runs one DEM impact per measured angle (6 impacts, each giving
//!   cnr and ctr). An impact that does not end (an overdamped ball that stays on the wall) has
//!   zero likelihood.
//!
//! [`run_study`] runs every class for each Young's modulus of the settings (the printed
//! E = 2.1e10 Pa and steel's 2.1e11 Pa, because the paper's posterior only makes sense with the
//! latter, see the report), and [`report`] writes the comparison with seed 003 Table 4.

use mbgc_output::say;
use mbgc_output::Output;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use mbgc::calibrate::bayes::class_probabilities;
use mbgc::calibrate::tmcmc::{tmcmc, TmcmcOptions, TmcmcResult, UniformBox};
use mbgc::dem::contact::{
    CohesionKind, ModelClass as ContactClass, NormalKind, RollingKind, TangentialKind,
};
use mbgc::error::{csv_error, csv_number, csv_open_str, write_atomic, Error, Result};
use mbgc::experiments::wall_impact::WallImpact;
use mbgc::experiments::{Experiment, ParamSet, RunOptions};

/// Which coefficient of restitution a measurement is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Response {
    /// Normal: `-v_n' / v_n` of the centre velocity.
    Cnr,
    /// Tangential: `v_t' / v_t` of the centre velocity.
    Ctr,
}

impl Response {
    pub fn name(self) -> &'static str {
        match self {
            Response::Cnr => "cnr",
            Response::Ctr => "ctr",
        }
    }
}

/// One measured coefficient of restitution with its standard deviation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ImpactMeasurement {
    /// Impact angle from the wall normal, degrees.
    pub angle_deg: f64,
    pub response: Response,
    pub value: f64,
    pub sd: f64,
}

const COLUMNS: [&str; 4] = ["impact_angle_deg", "type", "value", "sd"];

/// Reads the measurements (`impact_angle_deg,type,value,sd`; `#` lines are comments).
pub fn load_csv(path: &Path) -> Result<Vec<ImpactMeasurement>> {
    let text = mbgc::error::read_to_string(path)?;
    parse_csv(&text, &path.display().to_string())
}

/// Parses the measurement table with the shared CSV reader; errors name `file`, the line and
/// the column. The columns may come in any order; each must appear once.
pub fn parse_csv(text: &str, file: &str) -> Result<Vec<ImpactMeasurement>> {
    let (mut rdr, header) = csv_open_str(text, file)?;
    if header.iter().all(|h| h.is_empty()) {
        return Err(Error::input(
            file,
            "header",
            format!("no header line; expected {}", COLUMNS.join(",")),
        ));
    }
    for (i, h) in header.iter().enumerate() {
        if header[..i].contains(h) {
            return Err(Error::input(
                file,
                format!("header, column {h}"),
                "appears twice; a measurement needs one value per column",
            ));
        }
    }
    let mut idx = [0; 4];
    for (slot, col) in idx.iter_mut().zip(COLUMNS) {
        *slot = header.iter().position(|f| f == col).ok_or_else(|| {
            Error::input(
                file,
                "header",
                format!(
                    "missing column `{col}`; expected the columns {}",
                    COLUMNS.join(",")
                ),
            )
        })?;
    }
    let mut out = Vec::new();
    for rec in rdr.records() {
        let rec = rec.map_err(|e| csv_error(file, e))?;
        let line = rec.position().map_or(0, |p| p.line());
        let at = |c: usize| format!("line {line}, column {}", COLUMNS[c]);
        let num = |c: usize, lo: f64, hi: f64, what: &str| -> Result<f64> {
            let v = csv_number(file, line, COLUMNS[c], &rec[idx[c]])?;
            if !(v >= lo && v <= hi) {
                return Err(Error::input(
                    file,
                    at(c),
                    format!("expected {what}, found {v}"),
                ));
            }
            Ok(v)
        };
        let angle_deg = num(0, 0.0, 89.0, "an impact angle in (0, 89] degrees")?;
        if angle_deg == 0.0 {
            return Err(Error::input(
                file,
                at(0),
                "expected an oblique impact (angle > 0): ctr is undefined at 0 degrees",
            ));
        }
        let response = match &rec[idx[1]] {
            "cnr" => Response::Cnr,
            "ctr" => Response::Ctr,
            other => {
                return Err(Error::input(
                    file,
                    at(1),
                    format!("expected `cnr` or `ctr`, found `{other}`"),
                ))
            }
        };
        let value = num(2, -10.0, 10.0, "a coefficient of restitution in [-10, 10]")?;
        let sd = num(3, 0.0, f64::MAX, "a standard deviation > 0")?;
        if sd <= 0.0 {
            return Err(Error::input(
                file,
                at(3),
                "expected a standard deviation > 0, found 0",
            ));
        }
        out.push(ImpactMeasurement {
            angle_deg,
            response,
            value,
            sd,
        });
    }
    if out.is_empty() {
        return Err(Error::input(
            file,
            "rows",
            "no measurements after the header",
        ));
    }
    Ok(out)
}

/// The impact: particle, wall and speed. The paper's particle is a steel disk (2-D) of radius
/// 22.25 mm and mass 0.3538 kg; ours is a sphere of the same radius and mass.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Setup {
    /// Young's modulus of particle and wall, Pa.
    pub youngs_modulus: f64,
    pub poisson: f64,
    pub radius: f64,
    pub mass: f64,
    /// Impact speed, m/s (not given in seed 003).
    pub impact_speed: f64,
}

impl Setup {
    /// Seed 003 Sec. 4 with Young's modulus `youngs` and impact speed `speed`.
    pub fn seed003(youngs: f64, speed: f64) -> Self {
        Setup {
            youngs_modulus: youngs,
            poisson: 0.3,
            radius: 0.02225,
            mass: 0.3538,
            impact_speed: speed,
        }
    }

    /// Density that gives the sphere the paper's mass.
    pub fn density(&self) -> f64 {
        self.mass / (4.0 / 3.0 * std::f64::consts::PI * self.radius.powi(3))
    }

    /// The unit of the sampled k_t, N/m: 1e7 at the printed E = 2.1e10 Pa, scaled as
    /// E^(4/5) (a spring acts within one impact when its period is comparable with the Hertz
    /// contact time, and t_c^-2 grows as E^(4/5)).
    pub fn k_t_unit(&self) -> f64 {
        K_T_UNIT_AT_PRINTED * (self.youngs_modulus / E_PRINTED).powf(0.8)
    }

    /// Hertz contact time of an undamped impact at normal speed `v_n` against the wall,
    /// 2.87 (m^2 / (R Y*^2 v_n))^(1/5) (Johnson, Contact Mechanics, Sec. 11.4), s.
    pub fn hertz_contact_time(&self, v_n: f64) -> f64 {
        let y_eff = self.youngs_modulus / (2.0 * (1.0 - self.poisson * self.poisson));
        2.87 * (self.mass * self.mass / (self.radius * y_eff * y_eff * v_n)).powf(0.2)
    }

    /// Period 2 pi sqrt(m_t / k) of a tangential spring `k` (N/m) on the sphere's tangential
    /// effective mass m_t = m / (1 + m R^2 / I) = 2/7 m, s.
    pub fn tangential_period(&self, k: f64) -> f64 {
        2.0 * std::f64::consts::PI * (2.0 / 7.0 * self.mass / k).sqrt()
    }

    /// Hertz constant k_n = 4/3 Y* sqrt(R*) against a wall of the same material, N/m^1.5.
    pub fn k_n(&self) -> f64 {
        let y_eff = self.youngs_modulus / (2.0 * (1.0 - self.poisson * self.poisson));
        4.0 / 3.0 * y_eff * self.radius.sqrt()
    }
}

/// The normal-force classes of seed 003 Table 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum NormalModel {
    /// Tsuji: damping gamma_n d^(1/4) d'.
    M1,
    /// Kuwabara-Kono: gamma_n d^(1/2) d'.
    M2,
    /// Free exponent: gamma_n d^alpha_n d'.
    M3,
}

impl NormalModel {
    pub const ALL: [NormalModel; 3] = [NormalModel::M1, NormalModel::M2, NormalModel::M3];

    pub fn label(self) -> &'static str {
        match self {
            NormalModel::M1 => "M1",
            NormalModel::M2 => "M2",
            NormalModel::M3 => "M3",
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            NormalModel::M1 => "Tsuji, alpha_n = 1/4",
            NormalModel::M2 => "Kuwabara-Kono, alpha_n = 1/2",
            NormalModel::M3 => "free alpha_n",
        }
    }

    /// Fixed damping exponent, `None` for M3.
    pub fn fixed_alpha(self) -> Option<f64> {
        match self {
            NormalModel::M1 => Some(0.25),
            NormalModel::M2 => Some(0.5),
            NormalModel::M3 => None,
        }
    }

    /// Parameter names in the paper's order.
    pub fn parameter_names(self) -> Vec<&'static str> {
        let mut v = vec!["mu"];
        if self == NormalModel::M3 {
            v.push("alpha_n");
        }
        v.extend(["gamma_n", "k_t", "sigma1_sq", "sigma2_sq"]);
        v
    }

    /// The uniform prior of the class.
    pub fn prior(self, p: &Priors) -> UniformBox {
        let mut b = vec![p.mu];
        if self == NormalModel::M3 {
            b.push(p.alpha_n);
        }
        b.extend([p.gamma_n, p.k_t, p.sigma_sq, p.sigma_sq]);
        UniformBox {
            lower: b.iter().map(|r| r[0]).collect(),
            upper: b.iter().map(|r| r[1]).collect(),
        }
    }

    /// Splits `theta` into the contact parameters (k_t converted to N/m with `k_t_unit`) and
    /// the two model-error variances.
    pub fn split(self, theta: &[f64], k_t_unit: f64) -> (Contact, [f64; 2]) {
        let (alpha_n, rest) = match self.fixed_alpha() {
            Some(a) => (a, &theta[1..]),
            None => (theta[1], &theta[2..]),
        };
        (
            Contact {
                mu: theta[0],
                alpha_n,
                gamma_n: rest[0],
                k_t: rest[1] * k_t_unit,
            },
            [rest[2], rest[3]],
        )
    }
}

/// Contact parameters of one DEM impact.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Contact {
    pub mu: f64,
    pub alpha_n: f64,
    /// N s / m^(1 + alpha_n).
    pub gamma_n: f64,
    /// Tangential spring, N/m.
    pub k_t: f64,
}

/// Uniform prior ranges `[lo, hi]` (seed 003 Table 3 in SI units, see [`Priors::default`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Priors {
    pub mu: [f64; 2],
    pub alpha_n: [f64; 2],
    pub gamma_n: [f64; 2],
    /// In units of [`Setup::k_t_unit`].
    pub k_t: [f64; 2],
    /// Both model-error variances sigma1^2 (cnr) and sigma2^2 (ctr).
    pub sigma_sq: [f64; 2],
}

/// The unit of the sampled k_t at the printed modulus, N/m (see [`Setup::k_t_unit`]).
pub const K_T_UNIT_AT_PRINTED: f64 = 1e7;

impl Default for Priors {
    /// Table 3 read with Table 4's column labels: mu [0.05, 0.2], alpha_n [0.15, 1.35],
    /// gamma_n [0.1, 15] x 1e4 (Table 4 prints gamma_n = 0.81e4 ... 8.41e4), k_t [0.1, 15] in
    /// units of [`Setup::k_t_unit`] (Table 4: 0.99-1.04, modes at 0.4 and 1.33; the unit is not
    /// printed, and a spring below ~1e5 N/m does not act within one impact), sigma^2 [0, 0.01].
    fn default() -> Self {
        Priors {
            mu: [0.05, 0.2],
            alpha_n: [0.15, 1.35],
            gamma_n: [0.1e4, 15e4],
            k_t: [0.1, 15.0],
            sigma_sq: [0.0, 1e-2],
        }
    }
}

/// cnr and ctr of one DEM impact at `angle_deg` (the wall-impact experiment).
pub fn simulate(setup: &Setup, c: &Contact, angle_deg: f64) -> Result<(f64, f64)> {
    let p = ParamSet::from_pairs(&[
        ("E_p", setup.youngs_modulus),
        ("nu_p", setup.poisson),
        ("rho_p", setup.density()),
        ("d50", 2.0 * setup.radius * 1e3),
        ("E_w", setup.youngs_modulus),
        ("mu_pw", c.mu),
        ("impact_speed", setup.impact_speed),
        ("impact_angle", angle_deg),
        ("gamma_n_pw", c.gamma_n),
        ("alpha_n_pw", c.alpha_n),
        ("k_t_pw", c.k_t),
    ]);
    // No tangential dashpot: without Hertz's restitution, beta = 0 (normal damping is
    // gamma_n's).
    let exp = WallImpact {
        class: ContactClass {
            normal: NormalKind::PowerDamped,
            tangential: TangentialKind::LinearSpring,
            rolling: RollingKind::None,
            cohesion: CohesionKind::None,
            limit_force: false,
        },
    };
    let o = exp.run(&p, 0, &RunOptions::default())?;
    let get = |k: &str| o.get(k).unwrap_or(f64::NAN);
    Ok((get("cnr"), get("ctr")))
}

/// The likelihood of one model class on one setup.
#[derive(Clone, Debug)]
pub struct Likelihood<'a> {
    pub class: NormalModel,
    pub setup: Setup,
    pub data: &'a [ImpactMeasurement],
    /// Distinct impact angles, ascending; one impact each.
    pub angles: Vec<f64>,
    /// Index into `angles` of each measurement.
    index: Vec<usize>,
}

impl<'a> Likelihood<'a> {
    pub fn new(class: NormalModel, setup: Setup, data: &'a [ImpactMeasurement]) -> Self {
        let mut angles: Vec<f64> = data.iter().map(|m| m.angle_deg).collect();
        angles.sort_by(f64::total_cmp);
        angles.dedup();
        let index = data
            .iter()
            .map(|m| angles.iter().position(|&a| a == m.angle_deg).unwrap_or(0))
            .collect();
        Likelihood {
            class,
            setup,
            data,
            angles,
            index,
        }
    }

    /// Contact parameters (k_t in N/m) and model-error variances of `theta`.
    pub fn split(&self, theta: &[f64]) -> (Contact, [f64; 2]) {
        self.class.split(theta, self.setup.k_t_unit())
    }

    /// (cnr, ctr) at every angle.
    pub fn predictions(&self, c: &Contact) -> Result<Vec<(f64, f64)>> {
        self.angles
            .iter()
            .map(|&a| simulate(&self.setup, c, a))
            .collect()
    }

    /// ln L(theta); `-inf` if an impact fails (never separates) or predicts a non-finite value.
    pub fn ln_likelihood(&self, theta: &[f64]) -> f64 {
        let (c, s) = self.split(theta);
        match self.predictions(&c) {
            Ok(pred) => self.ln_likelihood_of(&pred, s),
            Err(_) => f64::NEG_INFINITY,
        }
    }

    /// ln L of given predictions with model-error variances `s = [sigma1^2, sigma2^2]`.
    pub fn ln_likelihood_of(&self, pred: &[(f64, f64)], s: [f64; 2]) -> f64 {
        let ln_2pi = (2.0 * std::f64::consts::PI).ln();
        let mut l = 0.0;
        for (m, &i) in self.data.iter().zip(&self.index) {
            let (g, s2) = match m.response {
                Response::Cnr => (pred[i].0, s[0]),
                Response::Ctr => (pred[i].1, s[1]),
            };
            if !g.is_finite() {
                return f64::NEG_INFINITY;
            }
            let var = m.sd * m.sd + s2 * m.value * m.value;
            l -= 0.5 * (ln_2pi + var.ln() + (m.value - g).powi(2) / var);
        }
        l
    }
}

/// Settings of a study.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StudySettings {
    /// TMCMC samples per stage.
    pub samples: usize,
    pub seed: u64,
    /// Threads (0: all cores).
    pub threads: usize,
    /// Metropolis steps per chain and stage before the recorded one.
    pub burn_in: usize,
    /// Independent TMCMC runs per class (seeds `seed`, `seed + 1`, ...): the evidence is their
    /// mean and its scatter is reported; the posterior pools their samples.
    pub replicates: usize,
    /// One group of runs per Young's modulus.
    pub youngs_moduli: Vec<f64>,
    pub impact_speed: f64,
    /// Other impact speeds at which every class is recalibrated (one run each) on the last
    /// modulus: seed 003 does not state the speed.
    pub speed_check: Vec<f64>,
    pub priors: Priors,
    pub classes: Vec<NormalModel>,
}

/// Young's modulus printed in seed 003 Sec. 4, Pa.
pub const E_PRINTED: f64 = 2.1e10;
/// Young's modulus of steel, Pa.
pub const E_STEEL: f64 = 2.1e11;
/// Impact speed assumed (seed 003 does not give it), m/s.
pub const DEFAULT_SPEED: f64 = 2.0;

impl StudySettings {
    /// The defaults: both moduli, 2 m/s (checked at 1 and 4 m/s), Table 3 priors, burn-in 40,
    /// 3 replicates, all three classes.
    pub fn new(samples: usize, seed: u64, threads: usize) -> Self {
        StudySettings {
            samples,
            seed,
            threads,
            burn_in: 40,
            replicates: 3,
            youngs_moduli: vec![E_PRINTED, E_STEEL],
            impact_speed: DEFAULT_SPEED,
            speed_check: vec![1.0, 4.0],
            priors: Priors::default(),
            classes: NormalModel::ALL.to_vec(),
        }
    }
}

/// Posterior summary of one parameter.
pub use mbgc::calibrate::bayes::Summary as ParameterSummary;

/// Posterior of one class on one setup.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassResult {
    pub class: NormalModel,
    pub parameters: Vec<ParameterSummary>,
    /// Mean log-evidence over the replicates.
    pub ln_evidence: f64,
    /// Log-evidence of each replicate.
    pub ln_evidence_replicates: Vec<f64>,
    /// Posterior probability among the classes of the same setup (equal prior odds).
    pub probability: f64,
    /// Tempering stages (of the first replicate).
    pub stages: usize,
    pub final_acceptance: f64,
    /// Likelihood evaluations, all replicates.
    pub evaluations: usize,
    pub wall_time_s: f64,
    /// Largest ln L among the posterior samples and that sample.
    pub max_ln_likelihood: f64,
    pub best: Vec<f64>,
    /// Posterior-robust predictions per angle (seed 003 Eqs. 14-15).
    pub robust: Vec<RobustPrediction>,
    /// Posterior share of k_t in [`K_T_BINS`] log-spaced bins over its prior (shows modes).
    pub k_t_histogram: Vec<f64>,
    /// Posterior correlation of ln gamma_n and alpha_n over the pooled samples (M3 only): the
    /// ridge seed 003 reports.
    #[serde(default)]
    pub ln_gamma_alpha_corr: Option<f64>,
}

/// Posterior-robust prediction of cnr and ctr at one angle: mean over the posterior samples
/// (Eq. 14), the sd of the sample predictions (parametric uncertainty) and the total sd with the
/// model error `sigma_g^2 y^2` added (Eq. 15).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustPrediction {
    pub angle_deg: f64,
    pub cnr: [f64; 3],
    pub ctr: [f64; 3],
}

/// Robust predictions over `samples` (impacts in parallel; failed impacts are skipped).
pub fn robust_predictions(like: &Likelihood, samples: &[Vec<f64>]) -> Vec<RobustPrediction> {
    use rayon::prelude::*;
    // (cnr, ctr) per angle and the model-error variances of each sample.
    type Run = (Vec<(f64, f64)>, [f64; 2]);
    let runs: Vec<Run> = samples
        .par_iter()
        .filter_map(|th| {
            let (c, s) = like.split(th);
            like.predictions(&c).ok().map(|p| (p, s))
        })
        .collect();
    let n = runs.len().max(1) as f64;
    like.angles
        .iter()
        .enumerate()
        .map(|(k, &a)| {
            let stats = |pick: &dyn Fn(&(f64, f64)) -> f64, g: usize| {
                let mean = runs.iter().map(|(p, _)| pick(&p[k])).sum::<f64>() / n;
                let var = runs
                    .iter()
                    .map(|(p, _)| (pick(&p[k]) - mean).powi(2))
                    .sum::<f64>()
                    / n;
                let model = runs
                    .iter()
                    .map(|(p, s)| s[g] * pick(&p[k]).powi(2))
                    .sum::<f64>()
                    / n;
                [mean, var.sqrt(), (var + model).sqrt()]
            };
            RobustPrediction {
                angle_deg: a,
                cnr: stats(&|p| p.0, 0),
                ctr: stats(&|p| p.1, 1),
            }
        })
        .collect()
}

/// Bins of [`ClassResult::k_t_histogram`].
pub const K_T_BINS: usize = 10;
/// Intervals of [`Group::ctr_k_t_sweep`].
pub const K_T_SWEEP: usize = 40;

/// All classes on one setup.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Group {
    pub setup: Setup,
    pub classes: Vec<ClassResult>,
    /// What the literal (SI) reading of Table 3 would give, at the M1 posterior mean: mean cnr
    /// with gamma_n = 15, and ctr at the smallest angle with k_t = 1.5e5 N/m.
    pub cnr_with_gamma_15: f64,
    pub ctr_with_k_t_1_5e5: f64,
    /// ctr at the smallest angle against k_t (in units of [`Setup::k_t_unit`], log-spaced over
    /// the prior), the other parameters at the first class's posterior mean: `[k_t, ctr]`.
    #[serde(default)]
    pub ctr_k_t_sweep: Vec<[f64; 2]>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Study {
    pub data_file: String,
    pub data: Vec<ImpactMeasurement>,
    pub settings: StudySettings,
    /// Wall time of one likelihood evaluation (all angles), one thread, ms.
    pub likelihood_ms: f64,
    pub groups: Vec<Group>,
    /// The speed check: all classes recalibrated at [`StudySettings::speed_check`] on the last
    /// modulus, one run each.
    #[serde(default)]
    pub speed_groups: Vec<Group>,
    pub wall_time_s: f64,
}

/// The study with the default settings ([`StudySettings::new`]).
pub fn run_study(csv: &Path, samples: usize, seed: u64, threads: usize) -> Result<Study> {
    run_study_with(csv, &StudySettings::new(samples, seed, threads))
}

/// The study with explicit settings.
pub fn run_study_with(csv: &Path, s: &StudySettings) -> Result<Study> {
    let data = load_csv(csv)?;
    let mut study = run_on(&data, s, |m| eprintln!("{m}"))?;
    study.data_file = csv.display().to_string();
    Ok(study)
}

/// The study on given measurements; `log` receives one line per finished class.
pub fn run_on(
    data: &[ImpactMeasurement],
    s: &StudySettings,
    log: impl Fn(&str) + Sync,
) -> Result<Study> {
    if s.youngs_moduli.is_empty() || s.classes.is_empty() {
        return Err(Error::invalid(
            "restitution study: no Young's modulus or no model class to run",
        ));
    }
    if !(s.impact_speed.is_finite() && s.impact_speed > 0.0) {
        return Err(Error::invalid(format!(
            "restitution study: impact speed must be > 0 m/s, found {}",
            s.impact_speed
        )));
    }
    let pool = {
        let mut b = rayon::ThreadPoolBuilder::new();
        if s.threads > 0 {
            b = b.num_threads(s.threads);
        }
        b.build()
            .map_err(|e| Error::invalid(format!("thread pool: {e}")))?
    };
    let t0 = Instant::now();
    let likelihood_ms = {
        let like = Likelihood::new(
            NormalModel::M1,
            Setup::seed003(s.youngs_moduli[0], s.impact_speed),
            data,
        );
        // At seed 003's M1 posterior mean: a typical point of the posterior stages.
        let theta = [0.109, 0.81e4, 0.99, 0.0045, 0.0016];
        let t = Instant::now();
        let n = 50;
        for _ in 0..n {
            std::hint::black_box(like.ln_likelihood(&theta));
        }
        t.elapsed().as_secs_f64() * 1e3 / n as f64
    };
    let mut groups = Vec::new();
    for &e in &s.youngs_moduli {
        let setup = Setup::seed003(e, s.impact_speed);
        groups.push(pool.install(|| run_group(&setup, data, s, &log))?);
    }
    let mut speed_groups = Vec::new();
    let e_last = s.youngs_moduli[s.youngs_moduli.len() - 1];
    for &v in &s.speed_check {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(format!(
                "restitution study: speed-check speeds must be > 0 m/s, found {v}"
            )));
        }
        if v == s.impact_speed {
            continue;
        }
        let one = StudySettings {
            replicates: 1,
            ..s.clone()
        };
        let setup = Setup::seed003(e_last, v);
        speed_groups.push(pool.install(|| run_group(&setup, data, &one, &log))?);
    }
    Ok(Study {
        data_file: String::new(),
        data: data.to_vec(),
        settings: s.clone(),
        likelihood_ms,
        groups,
        speed_groups,
        wall_time_s: t0.elapsed().as_secs_f64(),
    })
}

/// Every class on one setup (in the current rayon pool), with class probabilities and the
/// literal-reading checks.
fn run_group(
    setup: &Setup,
    data: &[ImpactMeasurement],
    s: &StudySettings,
    log: &(impl Fn(&str) + Sync),
) -> Result<Group> {
    let mut classes = Vec::new();
    for &class in &s.classes {
        let r = run_class(class, setup, data, s)?;
        log(&format!(
            "E = {:.2e} Pa, {} m/s, {}: ln Z = {:.2}, mu = {:.4}, {} stages, {} evaluations, {:.1} s",
            setup.youngs_modulus,
            setup.impact_speed,
            class.label(),
            r.ln_evidence,
            r.parameters[0].mean,
            r.stages,
            r.evaluations,
            r.wall_time_s
        ));
        classes.push(r);
    }
    let p = class_probabilities(&classes.iter().map(|c| c.ln_evidence).collect::<Vec<_>>());
    for (c, p) in classes.iter_mut().zip(p) {
        c.probability = p;
    }
    // The literal SI reading of Table 3, at the first class's posterior mean.
    let c0 = &classes[0];
    let means: Vec<f64> = c0.parameters.iter().map(|p| p.mean).collect();
    let (contact, _) = c0.class.split(&means, setup.k_t_unit());
    let lit_gamma = Contact {
        gamma_n: 15.0,
        ..contact
    };
    let cnr: Vec<f64> = data
        .iter()
        .filter(|m| m.response == Response::Cnr)
        .map(|m| simulate(setup, &lit_gamma, m.angle_deg).map_or(f64::NAN, |r| r.0))
        .collect();
    let amin = data
        .iter()
        .map(|m| m.angle_deg)
        .fold(f64::INFINITY, f64::min);
    let lit_kt = Contact {
        k_t: 1.5e5,
        ..contact
    };
    let (klo, khi) = (s.priors.k_t[0].ln(), s.priors.k_t[1].ln());
    let ctr_k_t_sweep = (0..=K_T_SWEEP)
        .map(|k| {
            let kt = (klo + (khi - klo) * k as f64 / K_T_SWEEP as f64).exp();
            let c = Contact {
                k_t: kt * setup.k_t_unit(),
                ..contact
            };
            [kt, simulate(setup, &c, amin).map_or(f64::NAN, |r| r.1)]
        })
        .collect();
    Ok(Group {
        setup: setup.clone(),
        cnr_with_gamma_15: cnr.iter().sum::<f64>() / cnr.len().max(1) as f64,
        ctr_with_k_t_1_5e5: simulate(setup, &lit_kt, amin).map_or(f64::NAN, |r| r.1),
        ctr_k_t_sweep,
        classes,
    })
}

/// TMCMC of one class on one setup (in the current rayon pool).
pub fn run_class(
    class: NormalModel,
    setup: &Setup,
    data: &[ImpactMeasurement],
    s: &StudySettings,
) -> Result<ClassResult> {
    let t = Instant::now();
    let like = Likelihood::new(class, setup.clone(), data);
    let prior = class.prior(&s.priors);
    let evaluations = AtomicUsize::new(0);
    let mut runs = Vec::new();
    for rep in 0..s.replicates.max(1) as u64 {
        let opts = TmcmcOptions {
            samples: s.samples,
            burn_in: s.burn_in,
            seed: s.seed.wrapping_add(rep),
            ..TmcmcOptions::default()
        };
        let r = tmcmc(
            &prior,
            |th: &[f64]| {
                evaluations.fetch_add(1, Ordering::Relaxed);
                like.ln_likelihood(th)
            },
            &opts,
        )
        .map_err(|e| {
            Error::invalid(format!(
                "{} (E = {:e}, seed {}): {e}",
                class.label(),
                setup.youngs_modulus,
                opts.seed
            ))
        })?;
        runs.push(r);
    }
    let ln_z: Vec<f64> = runs.iter().map(|r| r.ln_evidence).collect();
    let mut pooled = runs[0].clone();
    for r in &runs[1..] {
        pooled.samples.extend(r.samples.iter().cloned());
        pooled.ln_likelihood.extend(&r.ln_likelihood);
    }
    pooled.ln_evidence = ln_z.iter().sum::<f64>() / ln_z.len() as f64;
    let mut out = summarise(
        class,
        &like,
        &pooled,
        &s.priors,
        evaluations.into_inner(),
        t,
    );
    out.ln_evidence_replicates = ln_z;
    Ok(out)
}

fn summarise(
    class: NormalModel,
    like: &Likelihood,
    r: &TmcmcResult,
    priors: &Priors,
    evaluations: usize,
    t: Instant,
) -> ClassResult {
    let (mean, sd, cov) = (r.mean(), r.std(), r.cov());
    let parameters = class
        .parameter_names()
        .iter()
        .enumerate()
        .map(|(j, n)| ParameterSummary {
            name: n.to_string(),
            mean: mean[j],
            sd: sd[j],
            cov: cov[j],
            q05: r.quantile(j, 0.05),
            q95: r.quantile(j, 0.95),
        })
        .collect();
    let (ibest, max_ln_likelihood) =
        r.ln_likelihood
            .iter()
            .copied()
            .enumerate()
            .fold(
                (0, f64::NEG_INFINITY),
                |a, (i, l)| if l > a.1 { (i, l) } else { a },
            );
    let robust = robust_predictions(like, &r.samples);
    let best = r.samples.get(ibest).cloned().unwrap_or_default();
    let jk = class
        .parameter_names()
        .iter()
        .position(|n| *n == "k_t")
        .unwrap_or(0);
    let (lo, hi) = (priors.k_t[0].ln(), priors.k_t[1].ln());
    let mut k_t_histogram = vec![0.0; K_T_BINS];
    for x in &r.samples {
        let b = ((x[jk].ln() - lo) / (hi - lo) * K_T_BINS as f64).floor();
        k_t_histogram[(b.max(0.0) as usize).min(K_T_BINS - 1)] += 1.0 / r.samples.len() as f64;
    }
    let names = class.parameter_names();
    let col = |n: &str| names.iter().position(|x| *x == n);
    let ln_gamma_alpha_corr = col("alpha_n").zip(col("gamma_n")).map(|(ja, jg)| {
        let xs: Vec<f64> = r.samples.iter().map(|x| x[jg].ln()).collect();
        let ys: Vec<f64> = r.samples.iter().map(|x| x[ja]).collect();
        correlation(&xs, &ys)
    });
    ClassResult {
        class,
        parameters,
        ln_evidence: r.ln_evidence,
        ln_evidence_replicates: vec![r.ln_evidence],
        probability: f64::NAN,
        stages: r.stages.len(),
        final_acceptance: r.stages.last().map_or(f64::NAN, |st| st.acceptance),
        evaluations,
        wall_time_s: t.elapsed().as_secs_f64(),
        max_ln_likelihood,
        best,
        robust,
        k_t_histogram,
        ln_gamma_alpha_corr,
    }
}

/// Pearson correlation (NaN when either side has no spread).
fn correlation(xs: &[f64], ys: &[f64]) -> f64 {
    let n = xs.len() as f64;
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
    let syy: f64 = ys.iter().map(|y| (y - my).powi(2)).sum();
    sxy / (sxx * syy).sqrt()
}

/// One row of seed 003 Table 4 (gamma_n in N s/m^(1+alpha), k_t in the paper's unprinted unit,
/// sigma's as printed, i.e. variances).
#[derive(Clone, Copy, Debug)]
pub struct PaperRow {
    pub class: NormalModel,
    pub mu: (f64, f64),
    pub alpha_n: (f64, Option<f64>),
    pub gamma_n: (f64, f64),
    pub k_t: (f64, f64),
    pub sigma1_sq: f64,
    pub sigma2_sq: f64,
    pub ln_evidence: f64,
}

/// Seed 003 Table 4 (means and COV), columns as labelled there.
pub const PAPER_TABLE4: [PaperRow; 3] = [
    PaperRow {
        class: NormalModel::M1,
        mu: (0.109, 0.128),
        alpha_n: (0.25, None),
        gamma_n: (0.81e4, 0.172),
        k_t: (0.99, 0.351),
        sigma1_sq: 0.0045,
        sigma2_sq: 0.0016,
        ln_evidence: 15.46,
    },
    PaperRow {
        class: NormalModel::M2,
        mu: (0.108, 0.1177),
        alpha_n: (0.5, None),
        gamma_n: (8.41e4, 0.187),
        k_t: (1.01, 0.338),
        sigma1_sq: 0.0035,
        sigma2_sq: 0.0019,
        ln_evidence: 16.39,
    },
    PaperRow {
        class: NormalModel::M3,
        mu: (0.111, 0.095),
        alpha_n: (0.44, Some(0.0578)),
        gamma_n: (5.45e4, 0.555),
        k_t: (1.04, 0.279),
        sigma1_sq: 0.0045,
        sigma2_sq: 0.0007,
        ln_evidence: 22.41,
    },
];

fn param<'a>(c: &'a ClassResult, name: &str) -> Option<&'a ParameterSummary> {
    c.parameters.iter().find(|p| p.name == name)
}

fn mean_cov(p: Option<&ParameterSummary>, scale: f64, digits: usize) -> String {
    match p {
        Some(p) => format!("{:.*} ({:.1} %)", digits, p.mean / scale, 100.0 * p.cov),
        None => "-".into(),
    }
}

/// Sample sd of the replicates' log-evidences (NaN for one run).
fn ln_z_sd(c: &ClassResult) -> f64 {
    let z = &c.ln_evidence_replicates;
    let n = z.len() as f64;
    if z.len() < 2 {
        return f64::NAN;
    }
    let m = z.iter().sum::<f64>() / n;
    (z.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
}

/// Standard error of the mean log-evidence.
fn ln_z_se(c: &ClassResult) -> f64 {
    ln_z_sd(c) / (c.ln_evidence_replicates.len() as f64).sqrt()
}

fn ln_z_text(c: &ClassResult) -> String {
    let sd = ln_z_sd(c);
    if sd.is_nan() {
        format!("{:.2}", c.ln_evidence)
    } else {
        format!("{:.2} (sd {:.2})", c.ln_evidence, sd)
    }
}

fn ranking(ln_z: &[(NormalModel, f64)]) -> String {
    let mut v = ln_z.to_vec();
    v.sort_by(|a, b| b.1.total_cmp(&a.1));
    v.iter()
        .map(|(c, _)| c.label())
        .collect::<Vec<_>>()
        .join(" > ")
}

/// The Markdown report: settings, the side-by-side comparison with seed 003 Table 4 per Young's
/// modulus, posterior details, predictions against the measurements, the impact-speed check and
/// the discussion. `command` is printed as the command that regenerates it.
pub fn report(study: &Study, command: &str) -> String {
    let s = &study.settings;
    let mut o = String::new();
    let w = &mut o;
    let paper_p = class_probabilities(&PAPER_TABLE4.map(|r| r.ln_evidence));
    let paper_rank = ranking(&PAPER_TABLE4.map(|r| (r.class, r.ln_evidence)));
    let _ = writeln!(w, "# Seed 003 restitution study on DEM impacts\n");
    let _ = writeln!(
        w,
        "Hadjidoukas et al. (2014) calibrate three normal-force classes of a 2-D disk DEM to the \
         measured restitution of a steel ball on a steel wall (their Table 2) by TMCMC and rank the \
         classes by evidence (Table 4: mu about 0.11 in every class, M3 most probable). Here the \
         same calibration runs on mbgc's 3-D wall-impact experiment: every likelihood evaluation \
         runs one DEM impact per measured angle.\n"
    );
    let _ = writeln!(w, "```\n{command}\n```\n");
    let _ = writeln!(w, "## Settings\n");
    let _ = writeln!(
        w,
        "- Data: `{}`, {} measurements at {} angles ({} deg).",
        study.data_file,
        study.data.len(),
        study
            .groups
            .first()
            .map_or(0, |g| g.classes.first().map_or(0, |c| c.robust.len())),
        {
            let mut a: Vec<f64> = study.data.iter().map(|m| m.angle_deg).collect();
            a.sort_by(f64::total_cmp);
            a.dedup();
            a.iter()
                .map(|x| format!("{x}"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    );
    let st = Setup::seed003(E_PRINTED, s.impact_speed);
    let _ = writeln!(
        w,
        "- Particle: sphere, R = {} m, m = {} kg (density {:.0} kg/m3, so that the sphere has the \
         paper's mass), nu = {}; wall: same material, flat. Young's modulus: {} (one group of runs \
         each). Impact speed {} m/s (not given in seed 003; see the speed check).",
        st.radius,
        st.mass,
        st.density(),
        st.poisson,
        s.youngs_moduli
            .iter()
            .map(|e| format!("{e:.2e} Pa"))
            .collect::<Vec<_>>()
            .join(" and "),
        s.impact_speed
    );
    let _ = writeln!(
        w,
        "- Normal force: `F_n = k_n d^1.5 + gamma_n d^alpha_n d'`, k_n = 4/3 Y* sqrt(R) (Hertz, \
         Y* = E / (2 (1 - nu^2)) against the steel wall), M1 alpha_n = 1/4, M2 1/2, M3 free. \
         Tangential: constant spring k_t (N/m) capped at mu F_n, no dashpot (e_pw = 1). Velocity \
         Verlet, 400 steps per Hertz contact time."
    );
    let pr = &s.priors;
    let _ = writeln!(
        w,
        "- Priors (uniform): mu [{}, {}], alpha_n [{}, {}] (M3), gamma_n [{:.1e}, {:.1e}] N s/m^(1+alpha_n), \
         k_t [{}, {}] in units of u_E = 1e7 N/m (E / 2.1e10 Pa)^0.8 ({}), sigma1^2 (cnr) and \
         sigma2^2 (ctr) [{}, {}].",
        pr.mu[0], pr.mu[1], pr.alpha_n[0], pr.alpha_n[1], pr.gamma_n[0], pr.gamma_n[1],
        pr.k_t[0],
        pr.k_t[1],
        s.youngs_moduli
            .iter()
            .map(|&e| format!("{:.2e} N/m at E = {e:.1e} Pa", Setup::seed003(e, 1.0).k_t_unit()))
            .collect::<Vec<_>>()
            .join(", "),
        pr.sigma_sq[0],
        pr.sigma_sq[1]
    );
    let _ = writeln!(
        w,
        "- Likelihood: seed 003's prediction-error model, `measured = g(theta) + e`, \
         `var(e_r) = sd_r^2 + sigma_g^2 measured_r^2` with one sigma_g^2 per group (cnr: sigma1^2, \
         ctr: sigma2^2), the variances being the sampled parameters. (mbgc's generic \
         `calibrate --bayes` scales the model error with the prediction and samples one sigma; \
         the paper's form is used here.)"
    );
    let _ = writeln!(
        w,
        "- TMCMC: {} samples per stage, burn-in {} Metropolis steps per chain and stage, \
         c.o.v. target 1, {} independent run(s) per class (seeds {}..={}; the evidence is their \
         mean, the posterior pools their samples), {} threads. One likelihood evaluation ({} \
         impacts) at seed 003's M1 posterior mean: {:.2} ms on one thread. Whole study: {:.1} \
         min.\n",
        s.samples,
        s.burn_in,
        s.replicates.max(1),
        s.seed,
        s.seed + s.replicates.max(1) as u64 - 1,
        if s.threads == 0 {
            "all".to_string()
        } else {
            s.threads.to_string()
        },
        study
            .groups
            .first()
            .and_then(|g| g.classes.first())
            .map_or(0, |c| c.robust.len()),
        study.likelihood_ms,
        study.wall_time_s / 60.0
    );

    let _ = writeln!(w, "## Side by side with seed 003 Table 4\n");
    let _ = writeln!(
        w,
        "Mean (COV). gamma_n in 1e4 N s/m^(1+alpha_n); k_t in u_E for mbgc and in the paper's \
         unprinted unit for the paper; sigma^2 are the model-error variances (the paper's \
         columns sigma1, sigma2). Paper class probabilities from its log-evidences with equal \
         prior odds.\n"
    );
    let _ = writeln!(
        w,
        "| class | source | mu | alpha_n | gamma_n | k_t | sigma1^2 (cnr) | sigma2^2 (ctr) | ln evidence | P(class) |"
    );
    let _ = writeln!(w, "|---|---|---|---|---|---|---|---|---|---|");
    for (k, row) in PAPER_TABLE4.iter().enumerate() {
        let _ = writeln!(
            w,
            "| {} | seed 003 (2-D disk) | {:.3} ({:.1} %) | {} | {:.2} ({:.1} %) | {:.2} ({:.1} %) | {} | {} | {:.2} | {:.4} |",
            row.class.label(),
            row.mu.0,
            100.0 * row.mu.1,
            match row.alpha_n.1 {
                Some(c) => format!("{:.2} ({:.1} %)", row.alpha_n.0, 100.0 * c),
                None => format!("{} (fixed)", row.alpha_n.0),
            },
            row.gamma_n.0 / 1e4,
            100.0 * row.gamma_n.1,
            row.k_t.0,
            100.0 * row.k_t.1,
            row.sigma1_sq,
            row.sigma2_sq,
            row.ln_evidence,
            paper_p[k]
        );
        for g in &study.groups {
            if let Some(c) = g.classes.iter().find(|c| c.class == row.class) {
                let _ = writeln!(
                    w,
                    "| {} | mbgc, E = {:.1e} | {} | {} | {} | {} | {} | {} | {} | {:.4} |",
                    row.class.label(),
                    g.setup.youngs_modulus,
                    mean_cov(param(c, "mu"), 1.0, 3),
                    match param(c, "alpha_n") {
                        Some(p) => mean_cov(Some(p), 1.0, 2),
                        None => format!("{} (fixed)", row.alpha_n.0),
                    },
                    mean_cov(param(c, "gamma_n"), 1e4, 2),
                    mean_cov(param(c, "k_t"), 1.0, 2),
                    param(c, "sigma1_sq").map_or("-".into(), |p| format!("{:.4}", p.mean)),
                    param(c, "sigma2_sq").map_or("-".into(), |p| format!("{:.4}", p.mean)),
                    ln_z_text(c),
                    c.probability
                );
            }
        }
    }
    let _ = writeln!(w);
    let _ = writeln!(w, "Evidence ranking: seed 003 {paper_rank}.");
    for g in &study.groups {
        let r = ranking(
            &g.classes
                .iter()
                .map(|c| (c.class, c.ln_evidence))
                .collect::<Vec<_>>(),
        );
        let mut z: Vec<&ClassResult> = g.classes.iter().collect();
        z.sort_by(|a, b| b.ln_evidence.total_cmp(&a.ln_evidence));
        let gaps: Vec<String> = z
            .windows(2)
            .map(|p| {
                format!(
                    "{} - {} = {:.2} +- {:.2}",
                    p[0].class.label(),
                    p[1].class.label(),
                    p[0].ln_evidence - p[1].ln_evidence,
                    (ln_z_se(p[0]).powi(2) + ln_z_se(p[1]).powi(2)).sqrt()
                )
            })
            .collect();
        let _ = writeln!(
            w,
            "mbgc at E = {:.1e} Pa: {r}{}; gaps in ln evidence {} (standard error of the mean over \
             the replicates).",
            g.setup.youngs_modulus,
            if r == paper_rank {
                " (same order)"
            } else {
                " (differs)"
            },
            gaps.join(", ")
        );
    }
    let _ = writeln!(w);

    let _ = writeln!(w, "## Posterior details\n");
    for g in &study.groups {
        let _ = writeln!(w, "### E = {:.2e} Pa\n", g.setup.youngs_modulus);
        let _ = writeln!(
            w,
            "| class | parameter | mean | sd | COV | 5 % | 95 % |\n|---|---|---|---|---|---|---|"
        );
        for c in &g.classes {
            for p in &c.parameters {
                let _ = writeln!(
                    w,
                    "| {} | {} | {:.4e} | {:.3e} | {:.1} % | {:.4e} | {:.4e} |",
                    c.class.label(),
                    p.name,
                    p.mean,
                    p.sd,
                    100.0 * p.cov,
                    p.q05,
                    p.q95
                );
            }
        }
        let _ = writeln!(
            w,
            "\nk_t unit at this modulus: {:.3e} N/m.\n\n| class | ln evidence | per run | P(class) | max ln L | stages | final acceptance | likelihood evaluations | wall time |\n|---|---|---|---|---|---|---|---|---|",
            g.setup.k_t_unit()
        );
        for c in &g.classes {
            let _ = writeln!(
                w,
                "| {} ({}) | {} | {} | {:.4} | {:.2} | {} | {:.2} | {} | {:.0} s |",
                c.class.label(),
                c.class.description(),
                ln_z_text(c),
                c.ln_evidence_replicates
                    .iter()
                    .map(|z| format!("{z:.2}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                c.probability,
                c.max_ln_likelihood,
                c.stages,
                c.final_acceptance,
                c.evaluations,
                c.wall_time_s
            );
        }
        let edges: Vec<f64> = (0..=K_T_BINS)
            .map(|k| {
                let (lo, hi) = (s.priors.k_t[0].ln(), s.priors.k_t[1].ln());
                (lo + (hi - lo) * k as f64 / K_T_BINS as f64).exp()
            })
            .collect();
        let _ = writeln!(
            w,
            "\nPosterior share of k_t (in units of {:.2e} N/m) per log-spaced bin:\n",
            g.setup.k_t_unit()
        );
        let mut head = String::from("| class |");
        let mut sep = String::from("|---|");
        for k in 0..K_T_BINS {
            let _ = write!(head, " {:.2}-{:.2} |", edges[k], edges[k + 1]);
            sep.push_str("---|");
        }
        let _ = writeln!(w, "{head}\n{sep}");
        for c in &g.classes {
            let mut line = format!("| {} |", c.class.label());
            for f in &c.k_t_histogram {
                let _ = write!(line, " {:.2} |", f);
            }
            let _ = writeln!(w, "{line}");
        }
        let _ = writeln!(
            w,
            "\nPosterior-robust predictions (seed 003 Eqs. 14-15: mean over the posterior samples +- \
             total sd, parametric and model error) against the measurements (mean +- sd):\n"
        );
        let mut head = String::from("| angle | cnr measured |");
        let mut sep = String::from("|---|---|");
        for c in &g.classes {
            let _ = write!(head, " {} |", c.class.label());
            sep.push_str("---|");
        }
        head.push_str(" ctr measured |");
        sep.push_str("---|");
        for c in &g.classes {
            let _ = write!(head, " {} |", c.class.label());
            sep.push_str("---|");
        }
        let _ = writeln!(w, "{head}\n{sep}");
        let angles: Vec<f64> = g.classes[0].robust.iter().map(|p| p.angle_deg).collect();
        for (k, a) in angles.iter().enumerate() {
            let meas = |r: Response| {
                study
                    .data
                    .iter()
                    .find(|m| m.angle_deg == *a && m.response == r)
                    .map_or("-".into(), |m| format!("{:.3} +- {:.3}", m.value, m.sd))
            };
            let mut line = format!("| {a} | {} |", meas(Response::Cnr));
            for c in &g.classes {
                let _ = write!(
                    line,
                    " {} |",
                    c.robust.get(k).map_or("-".into(), |p| format!(
                        "{:.3} +- {:.3}",
                        p.cnr[0], p.cnr[2]
                    ))
                );
            }
            let _ = write!(line, " {} |", meas(Response::Ctr));
            for c in &g.classes {
                let _ = write!(
                    line,
                    " {} |",
                    c.robust.get(k).map_or("-".into(), |p| format!(
                        "{:.3} +- {:.3}",
                        p.ctr[0], p.ctr[2]
                    ))
                );
            }
            let _ = writeln!(w, "{line}");
        }
        let _ = writeln!(w);
    }

    if !study.speed_groups.is_empty() {
        let _ = writeln!(w, "## Impact speed check\n");
        let _ = writeln!(
            w,
            "Seed 003 does not state the impact speed. Every class recalibrated at other speeds on \
             E = {:.1e} Pa (one TMCMC run each, same settings otherwise; the {} m/s rows are the \
             main runs). k_t in N/m: a fixed spring acts through its period against the contact \
             time, t_c ~ v^(-1/5), so k_t should move as v^(2/5).\n",
            study.speed_groups[0].setup.youngs_modulus,
            s.impact_speed
        );
        let _ = writeln!(
            w,
            "| speed | class | ln evidence | P(class) | max ln L | mu | alpha_n | gamma_n (1e4) | k_t (N/m) |\n|---|---|---|---|---|---|---|---|---|"
        );
        let main = study
            .groups
            .iter()
            .rev()
            .find(|g| g.setup.youngs_modulus == study.speed_groups[0].setup.youngs_modulus);
        let mut rows: Vec<&Group> = main.into_iter().chain(&study.speed_groups).collect();
        rows.sort_by(|a, b| a.setup.impact_speed.total_cmp(&b.setup.impact_speed));
        for g in &rows {
            for c in &g.classes {
                let _ = writeln!(
                    w,
                    "| {} m/s | {} | {:.2} | {:.3} | {:.2} | {} | {} | {} | {} |",
                    g.setup.impact_speed,
                    c.class.label(),
                    c.ln_evidence,
                    c.probability,
                    c.max_ln_likelihood,
                    mean_cov(param(c, "mu"), 1.0, 3),
                    param(c, "alpha_n").map_or("-".into(), |p| mean_cov(Some(p), 1.0, 2)),
                    mean_cov(param(c, "gamma_n"), 1e4, 2),
                    param(c, "k_t").map_or("-".into(), |p| format!(
                        "{:.2e} ({:.0} %)",
                        p.mean * g.setup.k_t_unit(),
                        100.0 * p.cov
                    )),
                );
            }
        }
        let _ = writeln!(w);
        for g in &rows {
            let _ = writeln!(
                w,
                "Ranking at {} m/s: {}.",
                g.setup.impact_speed,
                ranking(
                    &g.classes
                        .iter()
                        .map(|c| (c.class, c.ln_evidence))
                        .collect::<Vec<_>>()
                )
            );
        }
        let _ = writeln!(w);
    }

    let _ = writeln!(w, "## Reading seed 003's tables\n");
    let lit = literal_reading(study);
    let _ = writeln!(
        w,
        "- Table 3 lists the priors as mu x gamma_n [0.1, 15] x k_t [0.1e4, 15e4], Table 4 prints \
         gamma_n = 0.81e4 / 8.41e4 / 5.45e4 and k_t = 0.99 / 1.01 / 1.04, and the text of Sec. 4 \
         agrees with Table 4 (gamma_n COV 17.2 % in M1, \"MAP 8.41 for M2 compared to 0.81 for \
         M1\", k_t peaks at 0.4 and 1.33, gamma_n of M3 over \"0.1 to 15\"). So gamma_n lives on \
         [0.1, 15] x 1e4 and k_t on [0.1, 15] in some unit; Table 3's two columns are swapped. \
         {} With the literal reading, the M1 posterior mean with gamma_n = 15 gives a mean cnr of \
         {} against the measured range {:.3}-{:.3} (values +- {LITERAL_TOL_SD} sd), and \
         k_t = 1.5e5 N/m gives ctr = {} at {} deg against the measured {:.3}-{:.3} (+- \
         {LITERAL_TOL_SD} sd). Such a spring's period 2 pi sqrt(2/7 m / k_t) is {:.1} ms, against \
         a Hertz contact time of {} at normal incidence.",
        match (lit.gamma_outside, lit.k_t_outside) {
            (true, true) => "The DEM confirms it: both literal values fall outside the measured range.",
            (true, false) => "The DEM confirms it for gamma_n only: the literal k_t stays inside the measured range.",
            (false, true) => "The DEM confirms it for k_t only: the literal gamma_n stays inside the measured range.",
            (false, false) => "The DEM does not decide it: both literal values stay inside the measured range.",
        },
        study
            .groups
            .iter()
            .map(|g| format!("{:.4} (E = {:.1e})", g.cnr_with_gamma_15, g.setup.youngs_modulus))
            .collect::<Vec<_>>()
            .join(" / "),
        lit.cnr_range.0,
        lit.cnr_range.1,
        study
            .groups
            .iter()
            .map(|g| format!("{:.3} (E = {:.1e})", g.ctr_with_k_t_1_5e5, g.setup.youngs_modulus))
            .collect::<Vec<_>>()
            .join(" / "),
        lit.angle,
        lit.ctr_range.0,
        lit.ctr_range.1,
        1e3 * st.tangential_period(1.5e5),
        study
            .groups
            .iter()
            .map(|g| format!(
                "{:.2} ms (E = {:.1e})",
                1e3 * g.setup.hertz_contact_time(s.impact_speed),
                g.setup.youngs_modulus
            ))
            .collect::<Vec<_>>()
            .join(" / "),
    );
    let _ = writeln!(
        w,
        "- k_t's unit is not printed. mbgc samples k_t on [{}, {}] in units of u_E = 1e7 N/m at \
         E = 2.1e10 Pa scaled as E^0.8 like 1/t_c^2, so that the spring's period against the \
         contact time covers the same range at every modulus: {}. The width ratio {:.0} equals \
         Table 3's (0.1e4 to 15e4), so the Occam factors are comparable. The k_t columns are \
         compared in shape (modes, COV), not in value.",
        s.priors.k_t[0],
        s.priors.k_t[1],
        study
            .groups
            .iter()
            .map(|g| {
                let u = g.setup.k_t_unit();
                format!(
                    "periods {:.2}-{:.2} ms over the prior against t_c = {:.2} ms at E = {:.1e}",
                    1e3 * g.setup.tangential_period(s.priors.k_t[1] * u),
                    1e3 * g.setup.tangential_period(s.priors.k_t[0] * u),
                    1e3 * g.setup.hertz_contact_time(g.setup.impact_speed),
                    g.setup.youngs_modulus
                )
            })
            .collect::<Vec<_>>()
            .join("; "),
        s.priors.k_t[1] / s.priors.k_t[0],
    );
    let m1 = &PAPER_TABLE4[0];
    let _ = writeln!(
        w,
        "- sigma1, sigma2 of Table 4 ({}, {} in M1) are variances: Sec. 4 calls them prediction \
         errors of 6.7 % and 4.0 %, i.e. their square roots ({:.1} % and {:.1} %). Here too the \
         sampled parameters are sigma^2 with the prior [{}, {}], and sigma1 belongs to cnr, \
         sigma2 to ctr (Sec. 4: Sigma_cnr = sigma1^2 diag(y_cnr^2)).\n",
        m1.sigma1_sq,
        m1.sigma2_sq,
        100.0 * m1.sigma1_sq.sqrt(),
        100.0 * m1.sigma2_sq.sqrt(),
        s.priors.sigma_sq[0],
        s.priors.sigma_sq[1]
    );
    discussion(study, w);
    o
}

// Tolerances of the report's verdicts. Each is printed next to the verdict it decides.

/// mu agrees with seed 003 when |mbgc mean - paper mean| is at most this many mbgc posterior sd.
pub const MU_TOL_SD: f64 = 1.0;
/// gamma_n matches at a modulus when mbgc / seed 003 of both M1 and M2 lies within this factor.
pub const GAMMA_FACTOR: f64 = 1.5;
/// A (ln gamma_n, alpha_n) ridge needs at least this posterior correlation in absolute value.
pub const RIDGE_CORR: f64 = 0.7;
/// gamma_n is unidentified when its 5-95 % interval covers at least this share of its prior.
pub const UNIDENTIFIED_SHARE: f64 = 0.5;
/// A k_t mode: a histogram bin with at least this posterior share, above its neighbours.
pub const MODE_MIN_SHARE: f64 = 0.05;
/// One evidence is above another when the gap exceeds this many standard errors of the gap.
pub const Z_TOL_SE: f64 = 2.0;
/// The free exponent "buys little" when M3's best ln L is less than this above M1's and M2's.
pub const FIT_GAIN_TOL: f64 = 1.0;
/// The measured cnr "barely follows" the normal speed when |correlation| is below this.
pub const TREND_CORR: f64 = 0.5;
/// The measured range of a literal-reading check: the values +- this many sd.
pub const LITERAL_TOL_SD: f64 = 2.0;

/// The literal SI reading of Table 3 against the measured ranges.
struct Literal {
    cnr_range: (f64, f64),
    angle: f64,
    ctr_range: (f64, f64),
    /// Every modulus puts the literal value outside the measured range.
    gamma_outside: bool,
    k_t_outside: bool,
}

fn literal_reading(study: &Study) -> Literal {
    let band = |ms: &mut dyn Iterator<Item = &ImpactMeasurement>| {
        ms.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), m| {
            (
                lo.min(m.value - LITERAL_TOL_SD * m.sd),
                hi.max(m.value + LITERAL_TOL_SD * m.sd),
            )
        })
    };
    let cnr_range = band(&mut study.data.iter().filter(|m| m.response == Response::Cnr));
    let angle = study
        .data
        .iter()
        .map(|m| m.angle_deg)
        .fold(f64::INFINITY, f64::min);
    let ctr_range = band(
        &mut study
            .data
            .iter()
            .filter(|m| m.response == Response::Ctr && m.angle_deg == angle),
    );
    let outside = |v: f64, r: (f64, f64)| v.is_finite() && (v < r.0 || v > r.1);
    Literal {
        cnr_range,
        angle,
        ctr_range,
        gamma_outside: !study.groups.is_empty()
            && study
                .groups
                .iter()
                .all(|g| outside(g.cnr_with_gamma_15, cnr_range)),
        k_t_outside: !study.groups.is_empty()
            && study
                .groups
                .iter()
                .all(|g| outside(g.ctr_with_k_t_1_5e5, ctr_range)),
    }
}

fn range_of(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

fn paper_row(c: NormalModel) -> &'static PaperRow {
    PAPER_TABLE4
        .iter()
        .find(|r| r.class == c)
        .expect("Table 4 has every class")
}

/// (mbgc mean - seed 003 mean) / mbgc posterior sd of mu.
fn mu_deviation(c: &ClassResult) -> f64 {
    param(c, "mu").map_or(f64::NAN, |p| (p.mean - paper_row(c.class).mu.0) / p.sd)
}

/// mbgc / seed 003 of the gamma_n posterior means of M1 and M2 in a group.
fn gamma_ratios(g: &Group) -> Vec<(NormalModel, f64)> {
    g.classes
        .iter()
        .filter(|c| c.class != NormalModel::M3)
        .filter_map(|c| {
            param(c, "gamma_n").map(|p| (c.class, p.mean / paper_row(c.class).gamma_n.0))
        })
        .collect()
}

/// gamma_n matches seed 003 at the group's modulus: both M1 and M2 within [`GAMMA_FACTOR`].
fn gamma_matches(g: &Group) -> bool {
    let r = gamma_ratios(g);
    r.len() == 2
        && r.iter()
            .all(|(_, x)| x.is_finite() && x.ln().abs() <= GAMMA_FACTOR.ln())
}

/// Whether M3's posterior shows the (ln gamma_n, alpha_n) ridge ([`RIDGE_CORR`]).
fn has_ridge(c: &ClassResult) -> bool {
    c.ln_gamma_alpha_corr.is_some_and(|r| r.abs() >= RIDGE_CORR)
}

fn k_t_edges(p: &Priors) -> Vec<f64> {
    let (lo, hi) = (p.k_t[0].ln(), p.k_t[1].ln());
    (0..=K_T_BINS)
        .map(|k| (lo + (hi - lo) * k as f64 / K_T_BINS as f64).exp())
        .collect()
}

/// Bins of a histogram that are modes: at least [`MODE_MIN_SHARE`], above the left neighbour
/// and not below the right one (so a two-bin plateau counts once).
fn mode_bins(h: &[f64]) -> Vec<usize> {
    (0..h.len())
        .filter(|&k| {
            h[k] >= MODE_MIN_SHARE
                && (k == 0 || h[k] > h[k - 1])
                && (k + 1 == h.len() || h[k] >= h[k + 1])
        })
        .collect()
}

/// The order of two evidences at [`Z_TOL_SE`]: `Some(true)` if `a` is above `b`, `Some(false)`
/// if below, `None` if the gap is within the tolerance or has no error estimate.
fn above(a: &ClassResult, b: &ClassResult) -> Option<bool> {
    let gap = a.ln_evidence - b.ln_evidence;
    let se = (ln_z_se(a).powi(2) + ln_z_se(b).powi(2)).sqrt();
    if !se.is_finite() || gap.abs() <= Z_TOL_SE * se {
        None
    } else {
        Some(gap > 0.0)
    }
}

/// ln(sqrt(2 pi) sd / prior width) of gamma_n: the Laplace estimate of its Occam factor.
fn occam(c: &ClassResult, p: &Priors) -> f64 {
    param(c, "gamma_n").map_or(f64::NAN, |q| {
        ((2.0 * std::f64::consts::PI).sqrt() * q.sd / (p.gamma_n[1] - p.gamma_n[0])).ln()
    })
}

/// M2 leads M1 on prior volume rather than fit: |delta max ln L| < |delta Occam factor|.
fn prior_volume_not_fit(m1: &ClassResult, m2: &ClassResult, p: &Priors) -> bool {
    (m2.max_ln_likelihood - m1.max_ln_likelihood).abs() < (occam(m2, p) - occam(m1, p)).abs()
}

/// The discussion: what agrees with seed 003 and what does not. Every verdict is computed from
/// the run's numbers against the tolerance printed with it.
fn discussion(study: &Study, w: &mut String) {
    let s = &study.settings;
    let _ = writeln!(w, "## Discussion: what agrees, what does not, and why\n");
    let all: Vec<(&Group, &ClassResult)> = study
        .groups
        .iter()
        .flat_map(|g| g.classes.iter().map(move |c| (g, c)))
        .collect();
    if all.is_empty() {
        return;
    }
    let mean_of = |c: &ClassResult, n: &str| param(c, n).map_or(f64::NAN, |p| p.mean);
    let cov_of = |c: &ClassResult, n: &str| param(c, n).map_or(f64::NAN, |p| p.cov);
    let at = |g: &Group| format!("E = {:.1e}", g.setup.youngs_modulus);
    let cnr_data: Vec<&ImpactMeasurement> = study
        .data
        .iter()
        .filter(|m| m.response == Response::Cnr)
        .collect();
    let e_mean = cnr_data.iter().map(|m| m.value).sum::<f64>() / cnr_data.len().max(1) as f64;

    // Friction.
    let (lo, hi) = range_of(all.iter().map(|(_, c)| mean_of(c, "mu")));
    let (plo, phi) = range_of(PAPER_TABLE4.iter().map(|r| r.mu.0));
    let (clo, chi) = range_of(all.iter().map(|(_, c)| cov_of(c, "mu")));
    let (pclo, pchi) = range_of(PAPER_TABLE4.iter().map(|r| r.mu.1));
    let devs: Vec<f64> = all.iter().map(|(_, c)| mu_deviation(c)).collect();
    let worst = devs.iter().fold(0.0f64, |a, d| a.max(d.abs()));
    let mu_agrees = devs.iter().all(|d| d.abs() <= MU_TOL_SD);
    let mu_ours = 0.5 * (lo + hi);
    // Rigid-body stick criterion tan(theta) < mu (1 + e) (1 + m R^2 / I).
    let stick_deg = |inertia: f64| {
        (mu_ours * (1.0 + e_mean) * (1.0 + 1.0 / inertia))
            .atan()
            .to_degrees()
    };
    let (stick_sphere, stick_disk) = (stick_deg(0.4), stick_deg(0.5));
    let mut angles: Vec<f64> = study.data.iter().map(|m| m.angle_deg).collect();
    angles.sort_by(f64::total_cmp);
    angles.dedup();
    let list = |v: Vec<f64>| {
        if v.is_empty() {
            "none".to_string()
        } else {
            v.iter()
                .map(|a| format!("{a}"))
                .collect::<Vec<_>>()
                .join(", ")
        }
    };
    let sliding_angles: Vec<f64> = angles
        .iter()
        .copied()
        .filter(|&a| a > stick_sphere)
        .collect();
    let sticking_both: Vec<f64> = angles
        .iter()
        .copied()
        .filter(|&a| a <= stick_sphere.min(stick_disk))
        .collect();
    let _ = writeln!(
        w,
        "**{}** Tolerance: |mbgc mean - seed 003 mean of the same class| <= {MU_TOL_SD} mbgc \
         posterior sd. Posterior means {lo:.3}-{hi:.3} over the classes and moduli (COV \
         {:.0}-{:.0} %) against seed 003's {plo:.3}-{phi:.3} (COV {:.1}-{:.1} %, Table 4); \
         deviations in posterior sd: {}. mu is set by the impacts that slide throughout the \
         contact: there the centre velocity obeys ctr = 1 - mu (1 + cnr) / tan(theta), which \
         depends neither on the moment of inertia (sphere 2/5 m R^2, disk 1/2 m R^2) nor on the \
         stiffnesses, so a 2-D disk and a 3-D sphere read the same mu off those impacts. Impacts \
         with tan(theta) < mu (1 + e) (1 + m R^2 / I) stick before they leave (rigid-body \
         theory): with mu = {mu_ours:.3} and the mean measured cnr {e_mean:.3}, below {:.0} deg \
         for the sphere and {:.0} deg for the disk. Measured angles that slide throughout on the \
         sphere: {} deg; angles that stick in both: {} deg (they inform mu less).\n",
        if mu_agrees {
            "Friction mu agrees.".to_string()
        } else {
            format!("Friction mu differs by up to {worst:.1} posterior sd.")
        },
        100.0 * clo,
        100.0 * chi,
        100.0 * pclo,
        100.0 * pchi,
        all.iter()
            .zip(&devs)
            .map(|((g, c), d)| format!("{} at {} {d:+.1}", c.class.label(), at(g)))
            .collect::<Vec<_>>()
            .join(", "),
        stick_sphere,
        stick_disk,
        list(sliding_angles),
        list(sticking_both),
    );

    // gamma_n.
    let with_ratios: Vec<&Group> = study
        .groups
        .iter()
        .filter(|g| gamma_ratios(g).len() == 2)
        .collect();
    if !with_ratios.is_empty() {
        let matching: Vec<&Group> = with_ratios
            .iter()
            .copied()
            .filter(|g| gamma_matches(g))
            .collect();
        let missing: Vec<&Group> = with_ratios
            .iter()
            .copied()
            .filter(|g| !gamma_matches(g))
            .collect();
        let names = |v: &[&Group]| {
            v.iter()
                .map(|g| format!("{:.1e} Pa", g.setup.youngs_modulus))
                .collect::<Vec<_>>()
                .join(" and ")
        };
        let headline = match (matching.is_empty(), missing.is_empty()) {
            (true, _) => "gamma_n matches at no modulus.".to_string(),
            (false, true) => format!("gamma_n matches at E = {}.", names(&matching)),
            (false, false) => format!(
                "gamma_n matches at E = {}, not at {}.",
                names(&matching),
                names(&missing)
            ),
        };
        let is = |g: &&Group, e: f64| g.setup.youngs_modulus == e;
        let verdict = if matching.iter().any(|g| is(g, E_STEEL))
            && missing.iter().any(|g| is(g, E_PRINTED))
        {
            "Seed 003's gamma_n values therefore belong to steel's E = 2.1e11 Pa, not to the \
             printed 2.10e10: the printed modulus is most likely a misprint (or not what its code \
             ran)."
        } else if matching.iter().any(|g| is(g, E_PRINTED))
            && missing.iter().any(|g| is(g, E_STEEL))
        {
            "Seed 003's gamma_n values are consistent with the modulus it prints."
        } else {
            ""
        };
        let scaling = match (
            study
                .groups
                .iter()
                .find(|g| g.setup.youngs_modulus == E_PRINTED),
            study
                .groups
                .iter()
                .find(|g| g.setup.youngs_modulus == E_STEEL),
        ) {
            (Some(a), Some(b)) => {
                let m1 = |g: &Group| {
                    g.classes
                        .iter()
                        .find(|c| c.class == NormalModel::M1)
                        .map_or(f64::NAN, |c| mean_of(c, "gamma_n"))
                };
                format!(
                    " For a given restitution gamma_n scales as sqrt(k_n m) ~ E^(1/2) in M1 \
                     (Tsuji's damping is speed-independent), a factor {:.2} between the two \
                     moduli; this run's M1 means differ by {:.2}.",
                    (E_STEEL / E_PRINTED).sqrt(),
                    m1(b) / m1(a)
                )
            }
            _ => String::new(),
        };
        let _ = writeln!(
            w,
            "**{headline}** Tolerance: mbgc / seed 003 of the posterior means within a factor \
             {GAMMA_FACTOR} for both M1 and M2. Both codes use the same normal law: seed 003 takes \
             the 3-D Hertz constant k_n = 4/3 E* sqrt(R*) even for its disks (Sec. 2), and its \
             gamma_n multiplies d^alpha_n d' in N s/m^(1+alpha_n) as mbgc's `gamma_n` does, so the \
             values compare directly once E and the mass are the same (the sphere's density, \
             {:.0} kg/m3, is set to give the paper's 0.3538 kg). Ratios mbgc / seed 003: {}.{scaling} \
             {verdict}\n",
            Setup::seed003(E_PRINTED, 1.0).density(),
            with_ratios
                .iter()
                .map(|g| format!(
                    "at {} Pa {}",
                    at(g),
                    gamma_ratios(g)
                        .iter()
                        .map(|(c, r)| format!("{} {r:.2}", c.label()))
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
                .collect::<Vec<_>>()
                .join("; "),
        );
    }

    // alpha_n and the ridge.
    let m3: Vec<(&Group, &ClassResult)> = all
        .iter()
        .copied()
        .filter(|(_, c)| c.class == NormalModel::M3)
        .collect();
    if !m3.is_empty() {
        let paper3 = paper_row(NormalModel::M3);
        let paper_alpha_cov = paper3.alpha_n.1.unwrap_or(f64::NAN);
        let ridge = m3.iter().all(|(_, c)| has_ridge(c));
        let alpha_devs: Vec<f64> = m3
            .iter()
            .map(|(_, c)| {
                param(c, "alpha_n").map_or(f64::NAN, |p| (p.mean - paper3.alpha_n.0) / p.sd)
            })
            .collect();
        let alpha_agrees = alpha_devs.iter().all(|d| d.abs() <= MU_TOL_SD);
        let wider = m3
            .iter()
            .all(|(_, c)| cov_of(c, "alpha_n") > paper_alpha_cov);
        let share = |c: &ClassResult| {
            param(c, "gamma_n").map_or(f64::NAN, |p| {
                (p.q95 - p.q05) / (s.priors.gamma_n[1] - s.priors.gamma_n[0])
            })
        };
        let unidentified = m3.iter().all(|(_, c)| share(c) >= UNIDENTIFIED_SHARE);
        let _ = writeln!(
            w,
            "**M3: {}; the exponent {} seed 003's and is {} determined.** Tolerances: a ridge needs \
             |corr(ln gamma_n, alpha_n)| >= {RIDGE_CORR} over the posterior samples; alpha_n \
             agrees within {MU_TOL_SD} posterior sd; gamma_n is unidentified when its 5-95 % \
             interval covers at least {:.0} % of its prior. mbgc: {} against seed 003's \
             {} (COV {:.1} %; gamma_n COV {:.1} %, Table 4; Sec. 4: gamma_n and alpha_n \"appear \
             highly correlated\"). gamma_n is {}. On a ridge a larger exponent needs a larger \
             gamma_n for the same dissipation (d^alpha_n falls with alpha_n for overlaps d below \
             1 m), and the mean of the parameters need not lie on the ridge: use the robust \
             predictions.\n",
            if ridge {
                "the (gamma_n, alpha_n) ridge is reproduced"
            } else {
                "the (gamma_n, alpha_n) ridge is not reproduced"
            },
            if alpha_agrees {
                "agrees with"
            } else {
                "differs from"
            },
            if wider {
                "less sharply"
            } else {
                "as sharply or more sharply"
            },
            100.0 * UNIDENTIFIED_SHARE,
            m3.iter()
                .zip(&alpha_devs)
                .map(|((g, c), d)| {
                    let a = param(c, "alpha_n");
                    format!(
                        "alpha_n = {:.2} (COV {:.0} %, 5-95 % {:.2}-{:.2}, {d:+.1} sd from seed \
                         003), corr(ln gamma_n, alpha_n) {:+.2}, gamma_n COV {:.0} % with its \
                         5-95 % interval over {:.0} % of the prior, at {}",
                        a.map_or(f64::NAN, |p| p.mean),
                        100.0 * a.map_or(f64::NAN, |p| p.cov),
                        a.map_or(f64::NAN, |p| p.q05),
                        a.map_or(f64::NAN, |p| p.q95),
                        c.ln_gamma_alpha_corr.unwrap_or(f64::NAN),
                        100.0 * cov_of(c, "gamma_n"),
                        100.0 * share(c),
                        at(g),
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
            paper3.alpha_n.0,
            100.0 * paper_alpha_cov,
            100.0 * paper3.gamma_n.1,
            if unidentified {
                "therefore not identified in mbgc either"
            } else {
                "constrained in mbgc, unlike in seed 003"
            },
        );
    }

    // k_t.
    let edges = k_t_edges(&s.priors);
    let counts: Vec<usize> = all
        .iter()
        .map(|(_, c)| mode_bins(&c.k_t_histogram).len())
        .collect();
    let bimodal = counts.iter().filter(|&&n| n == 2).count();
    let kt: Vec<String> = all
        .iter()
        .map(|(g, c)| {
            let m = mode_bins(&c.k_t_histogram);
            let h = &c.k_t_histogram;
            let desc = m
                .iter()
                .map(|&k| {
                    format!(
                        "{:.2}-{:.2} ({:.0} %)",
                        edges[k],
                        edges[k + 1],
                        100.0 * h[k]
                    )
                })
                .collect::<Vec<_>>();
            format!(
                "{} at {}: {} mode(s){}",
                c.class.label(),
                at(g),
                m.len(),
                if desc.is_empty() {
                    String::new()
                } else {
                    format!(", {}", desc.join(" and "))
                }
            )
        })
        .collect();
    let crossings: Vec<(&Group, Vec<f64>)> = study
        .groups
        .iter()
        .map(|g| (g, sweep_crossings(g, &study.data)))
        .collect();
    let two_roots = !crossings.is_empty() && crossings.iter().all(|(_, x)| x.len() >= 2);
    let y_min_angle = study
        .data
        .iter()
        .filter(|m| m.response == Response::Ctr)
        .min_by(|a, b| a.angle_deg.total_cmp(&b.angle_deg));
    let _ = writeln!(
        w,
        "**k_t: {}, in units that cannot be compared.** Tolerance: a mode is a log-spaced bin \
         holding at least {:.0} % of the posterior, above its left neighbour and not below its \
         right one. Seed 003 (Sec. 4) reports a bimodal k_t posterior in every class, peaks at \
         0.4 and 1.33, the upper about 2.1 times more probable. mbgc (bins in u_E, with their \
         posterior share): {}. With the other parameters at the M1 posterior mean, ctr at {} deg \
         equals the measured {} at k_t = {} (sweep over the prior){}. Values differ for \
         reasons of dimension: the tangential effective mass m / (1 + m R^2 / I) is 2/7 m for \
         the sphere and 1/3 m for the disk (a 14 % softer spring gives the sphere the same \
         period), the rigid-rolling ctr is 5/7 against 2/3, and k_t's unit is unknown.\n",
        if bimodal == counts.len() {
            "bimodal in every run, as in seed 003".to_string()
        } else {
            format!(
                "bimodal in {bimodal} of {} runs, seed 003 in every class",
                counts.len()
            )
        },
        100.0 * MODE_MIN_SHARE,
        kt.join("; "),
        y_min_angle.map_or(f64::NAN, |m| m.angle_deg),
        y_min_angle.map_or("-".into(), |m| format!("{:.3}", m.value)),
        crossings
            .iter()
            .map(|(g, x)| format!(
                "{} at {}",
                if x.is_empty() {
                    "none".to_string()
                } else {
                    format!(
                        "{} u_E",
                        x.iter()
                            .map(|k| format!("{k:.2}"))
                            .collect::<Vec<_>>()
                            .join(" and ")
                    )
                },
                at(g)
            ))
            .collect::<Vec<_>>()
            .join(", "),
        if two_roots {
            ": two stiffnesses fit that point at every modulus, so the data below the sticking \
             angle cannot tell them apart (the paper blames the missing data below 10 deg, the \
             same statement)"
        } else {
            ": the sweep does not show two stiffnesses fitting that point at every modulus, so \
             it does not explain the modes"
        },
    );

    // Model-error variances and where the fit misses.
    let (s1lo, s1hi) = range_of(all.iter().map(|(_, c)| mean_of(c, "sigma1_sq")));
    let (s2lo, s2hi) = range_of(all.iter().map(|(_, c)| mean_of(c, "sigma2_sq")));
    let (p1lo, p1hi) = range_of(PAPER_TABLE4.iter().map(|r| r.sigma1_sq));
    let (p2lo, p2hi) = range_of(PAPER_TABLE4.iter().map(|r| r.sigma2_sq));
    let (vlo, vhi) = range_of(
        all.iter()
            .flat_map(|(_, c)| [cov_of(c, "sigma1_sq"), cov_of(c, "sigma2_sq")]),
    );
    let best = study.groups.last().and_then(|g| {
        g.classes
            .iter()
            .max_by(|a, b| a.ln_evidence.total_cmp(&b.ln_evidence))
    });
    let misses = |r: Response| -> Vec<(f64, f64, f64, f64, f64)> {
        best.map(|c| {
            c.robust
                .iter()
                .filter_map(|p| {
                    let pick = if r == Response::Cnr { p.cnr } else { p.ctr };
                    study
                        .data
                        .iter()
                        .find(|m| m.angle_deg == p.angle_deg && m.response == r)
                        .map(|m| {
                            (
                                p.angle_deg,
                                pick[0],
                                m.value,
                                (pick[0] - m.value) / m.sd,
                                pick[2],
                            )
                        })
                })
                .collect()
        })
        .unwrap_or_default()
    };
    let cnr_fit = misses(Response::Cnr);
    let (cplo, cphi) = range_of(cnr_fit.iter().map(|x| x.1));
    let cnr_inside = cnr_fit
        .iter()
        .filter(|(_, g, y, _, tot)| (g - y).abs() <= *tot)
        .count();
    let mut ctr_fit = misses(Response::Ctr);
    ctr_fit.sort_by(|a, b| b.3.abs().total_cmp(&a.3.abs()));
    // mu implied by each sliding impact, with the sd its ctr measurement gives it.
    let implied: Vec<(f64, f64, f64)> = study
        .data
        .iter()
        .filter(|m| m.response == Response::Ctr && m.angle_deg > stick_sphere)
        .map(|m| {
            let t = m.angle_deg.to_radians().tan() / (1.0 + e_mean);
            (m.angle_deg, (1.0 - m.value) * t, m.sd * t)
        })
        .collect();
    let wsum: f64 = implied.iter().map(|x| x.2.powi(-2)).sum();
    let mu_w = implied.iter().map(|x| x.1 * x.2.powi(-2)).sum::<f64>() / wsum;
    let consistent = implied.iter().all(|x| (x.1 - mu_w).abs() <= x.2);
    let _ = writeln!(
        w,
        "**Model-error variances.** mbgc: sigma1^2 (cnr) {s1lo:.4}-{s1hi:.4}, sigma2^2 (ctr) \
         {s2lo:.4}-{s2hi:.4} (posterior COV {:.0}-{:.0} %); seed 003: {p1lo:.4}-{p1hi:.4} and \
         {p2lo:.4}-{p2hi:.4} (Table 4). With the most probable class at the last modulus{}, the \
         robust cnr varies over {cplo:.3}-{cphi:.3} across the angles and lies within one total \
         sd of the measured cnr at {cnr_inside} of {} angles; its largest ctr misses are {}. The \
         rigid-rolling limit of ctr is 5/7 for a sphere and 2/3 for a disk. The sliding impacts \
         ({} deg) imply mu = {} from ctr = 1 - mu (1 + {e_mean:.3}) / tan(theta) with the mean \
         measured cnr; {} (tolerance: each within its own sd of the weighted mean {mu_w:.3}).\n",
        100.0 * vlo,
        100.0 * vhi,
        best.map_or(String::new(), |c| format!(" ({})", c.class.label())),
        cnr_fit.len(),
        ctr_fit
            .iter()
            .take(2)
            .map(|(a, g, y, z, _)| format!("{a} deg {g:.3} against {y:.3} ({z:+.1} sd)"))
            .collect::<Vec<_>>()
            .join(", "),
        list(implied.iter().map(|x| x.0).collect()),
        implied
            .iter()
            .map(|(a, m, sd)| format!("{m:.3} +- {sd:.3} at {a} deg"))
            .collect::<Vec<_>>()
            .join(", "),
        if implied.is_empty() {
            "no sliding impact to compare"
        } else if consistent {
            "these agree within their measurement sd, so one mu fits them all"
        } else {
            "these differ beyond their measurement sd, which only the ctr model error can absorb"
        },
    );

    evidence_paragraph(study, w, &all);
    speed_paragraph(study, w);
}

/// k_t values (u_E) where the sweep's ctr crosses the measured ctr at the smallest angle,
/// interpolated in ln k_t.
fn sweep_crossings(g: &Group, data: &[ImpactMeasurement]) -> Vec<f64> {
    let Some(y) = data
        .iter()
        .filter(|m| m.response == Response::Ctr)
        .min_by(|a, b| a.angle_deg.total_cmp(&b.angle_deg))
        .map(|m| m.value)
    else {
        return vec![];
    };
    g.ctr_k_t_sweep
        .windows(2)
        .filter_map(|p| {
            let (a, b) = (p[0][1] - y, p[1][1] - y);
            if !(a.is_finite() && b.is_finite()) || a * b > 0.0 || a == b {
                return None;
            }
            // A touch at the right end is counted by the next pair.
            if b == 0.0 {
                return None;
            }
            let t = a / (a - b);
            Some((p[0][0].ln() + t * (p[1][0].ln() - p[0][0].ln())).exp())
        })
        .collect()
}

fn class_of(g: &Group, cl: NormalModel) -> Option<&ClassResult> {
    g.classes.iter().find(|c| c.class == cl)
}

fn evidence_paragraph(study: &Study, w: &mut String, all: &[(&Group, &ClassResult)]) {
    let s = &study.settings;
    let paper_rank = ranking(&PAPER_TABLE4.map(|r| (r.class, r.ln_evidence)));
    let paper_p = class_probabilities(&PAPER_TABLE4.map(|r| r.ln_evidence));
    let [p1, p2, p3] = PAPER_TABLE4;
    let mut ev = Vec::new();
    let (mut m2m1, mut m3top, mut volume, mut little) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for g in &study.groups {
        let r = ranking(
            &g.classes
                .iter()
                .map(|c| (c.class, c.ln_evidence))
                .collect::<Vec<_>>(),
        );
        let mut t = format!("at E = {:.1e} Pa the order is {r}", g.setup.youngs_modulus);
        if let (Some(m1), Some(m2)) = (class_of(g, NormalModel::M1), class_of(g, NormalModel::M2)) {
            m2m1.push(above(m2, m1));
            volume.push(prior_volume_not_fit(m1, m2, &s.priors));
            let _ = write!(
                t,
                "; M2 - M1 = {:.2} +- {:.2} in ln evidence while their best fits differ by {:.2} \
                 in ln L and the gamma_n Occam factors ln(sqrt(2 pi) sd / prior width) by {:.2}; \
                 M2's gamma_n mean is {:.1} times M1's",
                m2.ln_evidence - m1.ln_evidence,
                (ln_z_se(m1).powi(2) + ln_z_se(m2).powi(2)).sqrt(),
                m2.max_ln_likelihood - m1.max_ln_likelihood,
                occam(m2, &s.priors) - occam(m1, &s.priors),
                param(m2, "gamma_n").map_or(f64::NAN, |p| p.mean)
                    / param(m1, "gamma_n").map_or(f64::NAN, |p| p.mean),
            );
        }
        if let Some(m3) = class_of(g, NormalModel::M3) {
            let others: Vec<&ClassResult> = g
                .classes
                .iter()
                .filter(|c| c.class != NormalModel::M3)
                .collect();
            let order: Vec<Option<bool>> = others.iter().map(|c| above(m3, c)).collect();
            m3top.push(if order.iter().all(|o| *o == Some(true)) {
                Some(true)
            } else if order.contains(&Some(false)) {
                Some(false)
            } else {
                None
            });
            let b12 = others
                .iter()
                .map(|c| c.max_ln_likelihood)
                .fold(f64::NEG_INFINITY, f64::max);
            let gain = m3.max_ln_likelihood - b12;
            little.push(gain < FIT_GAIN_TOL);
            let _ = write!(
                t,
                "; M3's best fit differs by {gain:+.2} in ln L from the better of M1 and M2"
            );
        }
        ev.push(t);
    }
    let word = |v: &[Option<bool>], yes: &str, no: &str| {
        if v.is_empty() {
            "is not tested".to_string()
        } else if v.iter().all(|o| *o == Some(true)) {
            yes.to_string()
        } else if v.contains(&Some(false)) {
            no.to_string()
        } else {
            format!("is not resolved at {Z_TOL_SE} standard errors")
        }
    };
    let (zlo, zhi) = range_of(all.iter().map(|(_, c)| c.ln_evidence));
    let (pzlo, pzhi) = range_of(PAPER_TABLE4.iter().map(|r| r.ln_evidence));
    let cnr_data: Vec<&ImpactMeasurement> = study
        .data
        .iter()
        .filter(|m| m.response == Response::Cnr)
        .collect();
    let corr = correlation(
        &cnr_data
            .iter()
            .map(|m| m.angle_deg.to_radians().cos())
            .collect::<Vec<_>>(),
        &cnr_data.iter().map(|m| m.value).collect::<Vec<_>>(),
    );
    let (ylo, yhi) = range_of(cnr_data.iter().map(|m| m.value));
    let m2_leads = !m2m1.is_empty() && m2m1.iter().all(|o| *o == Some(true));
    let vol_all = !volume.is_empty() && volume.iter().all(|v| *v);
    let volume_text = if m2_leads && vol_all {
        "M2 beats M1 on prior volume, not on fit (|delta max ln L| < |delta Occam factor| at \
         every modulus): both share the gamma_n prior, and M1's gamma_n (Tsuji) needs a much \
         smaller value for the same restitution, so with a similar COV it occupies a smaller \
         share of that prior."
            .to_string()
    } else if m2_leads {
        "M2's lead over M1 is not explained by prior volume alone (|delta max ln L| >= |delta \
         Occam factor| at some modulus)."
            .to_string()
    } else {
        "M2 does not lead M1 at every modulus, so there is no lead to attribute.".to_string()
    };
    // The same Laplace estimate on Table 4's gamma_n means and COVs (the prior width cancels).
    let paper_occam = (p2.gamma_n.0 * p2.gamma_n.1 / (p1.gamma_n.0 * p1.gamma_n.1)).ln();
    let paper_gap = p2.ln_evidence - p1.ln_evidence;
    let paper_fit = paper_gap - paper_occam;
    let alpha_span = all
        .iter()
        .filter(|(_, c)| c.class == NormalModel::M3)
        .filter_map(|(_, c)| param(c, "alpha_n"))
        .map(|p| (p.q95 - p.q05) / (s.priors.alpha_n[1] - s.priors.alpha_n[0]))
        .fold(f64::NEG_INFINITY, f64::max);
    let little_all = !little.is_empty() && little.iter().all(|l| *l);
    let _ = writeln!(
        w,
        "**Evidence ranking: M2 over M1 {}, M3 on top {}.** Tolerance: one class is above \
         another when its mean ln evidence is higher by more than {Z_TOL_SE} standard errors of \
         the gap (replicate scatter). Seed 003 finds {paper_rank} with ln evidence {:.2}, {:.2} \
         and {:.2} (Table 4; P(M3) {:.3}, M2 ahead of M1 by {:.2}). In mbgc {}. mbgc's \
         log-evidences span {zlo:.1}-{zhi:.1}, the paper's {pzlo:.1}-{pzhi:.1}; both use the \
         same data and error model. {volume_text} By the same estimate on Table 4's gamma_n \
         means and COVs, the paper's M2 gains {paper_occam:.2} in Occam factor over its M1, so \
         its gap of {paper_gap:.2} implies that its {} fits better by {:.2} in ln L. M3 contains \
         M1 and M2 (alpha_n = 1/4, 1/2), so its best fit cannot be worse in principle; {} \
         alpha_n can only shape the trend of cnr with the normal speed v cos(theta) (1 - e \
         grows as v_n^((4 alpha_n - 1)/5)), and the measured cnr ({ylo:.3}-{yhi:.3}) has a \
         correlation of {corr:+.2} with cos(theta) ({} the trend tolerance |r| < {TREND_CORR}); \
         M3's alpha_n 5-95 % interval covers at most {:.0} % of its prior [{}, {}]. Seed 003's \
         M3 is {:.2} above its better other class, and its sigma2^2 is {} in M3 against {} in M1 \
         (Table 4), so {}. Single TMCMC runs scatter: the replicate sd is in the tables above \
         (largest for {}).\n",
        word(&m2m1, "agrees", "does not hold"),
        word(&m3top, "agrees too", "does not"),
        p3.ln_evidence,
        p2.ln_evidence,
        p1.ln_evidence,
        paper_p[2],
        paper_gap,
        ev.join("; "),
        if paper_fit < 0.0 { "M1" } else { "M2" },
        paper_fit.abs(),
        if little_all {
            format!(
                "on the sphere the free exponent buys little (M3's best ln L is less than \
                 {FIT_GAIN_TOL} above the better of M1 and M2 at every modulus):"
            )
        } else {
            format!(
                "here the free exponent improves the best fit by at least {FIT_GAIN_TOL} in ln L \
                 at some modulus:"
            )
        },
        if corr.abs() < TREND_CORR {
            "within"
        } else {
            "outside"
        },
        100.0 * alpha_span,
        s.priors.alpha_n[0],
        s.priors.alpha_n[1],
        p3.ln_evidence - p2.ln_evidence.max(p1.ln_evidence),
        p3.sigma2_sq,
        p1.sigma2_sq,
        if p3.sigma2_sq < p1.sigma2_sq {
            "its M3 needs less ctr model error than its M1"
        } else {
            "its M3 does not need less ctr model error than its M1"
        },
        all.iter()
            .max_by(|a, b| ln_z_sd(a.1).total_cmp(&ln_z_sd(b.1)))
            .map_or("-".into(), |(g, c)| format!(
                "{} at E = {:.1e}, sd {:.2}",
                c.class.label(),
                g.setup.youngs_modulus,
                ln_z_sd(c)
            ))
    );
}

fn speed_paragraph(study: &Study, w: &mut String) {
    let s = &study.settings;
    let mean_of = |c: &ClassResult, n: &str| param(c, n).map_or(f64::NAN, |p| p.mean);
    let mut sp = String::new();
    if !study.speed_groups.is_empty() {
        let e = study.speed_groups[0].setup.youngs_modulus;
        let main = study
            .groups
            .iter()
            .rev()
            .find(|g| g.setup.youngs_modulus == e);
        let mut rows: Vec<&Group> = main.into_iter().chain(&study.speed_groups).collect();
        rows.sort_by(|a, b| a.setup.impact_speed.total_cmp(&b.setup.impact_speed));
        let cls = || rows.iter().flat_map(|g| g.classes.iter());
        let (mlo, mhi) = range_of(cls().map(|c| mean_of(c, "mu")));
        let mu_sd = cls()
            .filter_map(|c| param(c, "mu").map(|p| p.sd))
            .fold(f64::INFINITY, f64::min);
        let ranks: Vec<String> = rows
            .iter()
            .map(|g| {
                format!(
                    "{} at {} m/s",
                    ranking(
                        &g.classes
                            .iter()
                            .map(|c| (c.class, c.ln_evidence))
                            .collect::<Vec<_>>()
                    ),
                    g.setup.impact_speed
                )
            })
            .collect();
        // M1's k_t in N/m per speed, with its posterior sd.
        let kt: Vec<(f64, f64, f64)> = rows
            .iter()
            .filter_map(|g| {
                g.classes
                    .iter()
                    .find(|c| c.class == NormalModel::M1)
                    .and_then(|c| param(c, "k_t"))
                    .map(|p| {
                        let u = g.setup.k_t_unit();
                        (g.setup.impact_speed, p.mean * u, p.sd * u)
                    })
            })
            .collect();
        let (klo, khi) = range_of(kt.iter().map(|x| x.1));
        let k_sd = kt.iter().map(|x| x.2).fold(f64::INFINITY, f64::min);
        let mu_still = mhi - mlo <= mu_sd;
        let k_moves = kt.len() >= 2 && khi - klo > k_sd;
        let slope = match (kt.first(), kt.last()) {
            (Some(a), Some(b)) if kt.len() >= 2 => (b.1 / a.1).ln() / (b.0 / a.0).ln(),
            _ => f64::NAN,
        };
        sp = format!(
            "Recalibrated at other speeds (E = {e:.1e} Pa), the mu means span {mlo:.3}-{mhi:.3} \
             ({} the smallest posterior sd, {mu_sd:.3}), the ranking reads {}, and the M1 k_t \
             mean is {} ({} the smallest posterior sd, {k_sd:.2e} N/m; log-log slope against \
             the speed {slope:.2}, where a fixed spring's period matched to the contact time \
             t_c ~ v^(-1/5) gives 0.4){}. ",
            if mu_still { "within" } else { "more than" },
            ranks.join(", "),
            kt.iter()
                .map(|(v, k, _)| format!("{k:.2e} N/m at {v} m/s"))
                .collect::<Vec<_>>()
                .join(", "),
            if k_moves {
                "moving by more than"
            } else {
                "moving within"
            },
            match (k_moves, mu_still) {
                (true, true) => ": the k_t values are tied to the assumed speed, mu is not",
                (false, true) =>
                    ": neither mu nor k_t depends on the assumed speed at this tolerance",
                (true, false) => ": both mu and k_t move with the assumed speed",
                (false, false) => ": mu moves with the assumed speed more than k_t does",
            }
        );
    }
    let _ = writeln!(
        w,
        "**Unknowns and smaller differences.** The impact speed is not in seed 003. {sp}The wall \
         is a flat plane here and a phantom disk of very small curvature there (Sec. 2; both \
         R* = R). Seed 003 integrates with a third-order Gear predictor-corrector at 1e-6 s \
         (Sec. 2), mbgc with velocity Verlet at 1/400 of the Hertz contact time. At the Coulomb \
         cap seed 003 stops integrating the spring (the Heaviside in its Eq. 3) while mbgc resets \
         it to mu F_n / k_t (LIGGGHTS' rule); neither has a tangential dashpot. A likelihood \
         evaluation is {} impacts, {:.2} ms on one thread; the whole study took {:.1} min on {} \
         threads.\n",
        study
            .groups
            .first()
            .and_then(|g| g.classes.first())
            .map_or(0, |c| c.robust.len()),
        study.likelihood_ms,
        study.wall_time_s / 60.0,
        if s.threads == 0 {
            "all".to_string()
        } else {
            s.threads.to_string()
        }
    );
}

/// `mbgc bench restitution`.
#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    /// Measured restitution, columns impact_angle_deg,type,value,sd (seed 003 Table 2:
    /// examples/restitution_steel.csv).
    #[cfg_attr(feature = "cli", arg(long))]
    pub data: PathBuf,
    /// TMCMC samples per stage.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 2000))]
    pub samples: usize,
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1))]
    pub seed: u64,
    /// Threads (0: all cores); the result does not depend on it.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 0))]
    pub threads: usize,
    /// Metropolis steps per chain and stage before the recorded one.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 40))]
    pub burn_in: usize,
    /// Independent TMCMC runs per class (seeds seed, seed+1, ...): evidence scatter.
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 3))]
    pub replicates: usize,
    /// Young's moduli of particle and wall, Pa, one group of runs each (comma-separated).
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', default_values_t = [2.1e10, 2.1e11]))]
    pub youngs: Vec<f64>,
    /// Impact speed, m/s (seed 003 does not state it).
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 2.0))]
    pub speed: f64,
    /// Other speeds at which every class is recalibrated on the last modulus (one run each);
    /// give the flag without values to skip.
    #[cfg_attr(feature = "cli", arg(long, value_delimiter = ',', num_args = 0.., default_values_t = [1.0, 4.0]))]
    pub speed_check: Vec<f64>,
    /// Markdown report (e.g. docs/bayes_restitution.md).
    #[cfg_attr(feature = "cli", arg(long))]
    pub report: Option<PathBuf>,
    /// Standard output holds one JSON object (the results); the text goes to standard error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
    if let Some(report) = &a.report {
        mbgc::outputs::refuse_overwriting_inputs("--report", report, &[("--data", &a.data)])?;
    }
    let settings = StudySettings {
        burn_in: a.burn_in,
        replicates: a.replicates,
        youngs_moduli: a.youngs.clone(),
        impact_speed: a.speed,
        speed_check: a.speed_check.clone(),
        ..StudySettings::new(a.samples, a.seed, a.threads)
    };
    let study = run_study_with(&a.data, &settings)?;
    let command = format!(
        "cargo run --release -- bench restitution --data {} --samples {} --seed {} --threads {} --burn-in {} --replicates {} --youngs {} --speed {} --speed-check {}{}",
        a.data.display(),
        a.samples,
        a.seed,
        a.threads,
        a.burn_in,
        a.replicates,
        a.youngs
            .iter()
            .map(|e| format!("{e:e}"))
            .collect::<Vec<_>>()
            .join(","),
        a.speed,
        a.speed_check
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(","),
        a.report
            .as_ref()
            .map(|p| format!(" --report {}", p.display()))
            .unwrap_or_default()
    );
    let text = report(&study, &command);
    let out = Output::new(a.json);
    match &a.report {
        Some(p) => {
            write_atomic(p, text.as_bytes())?;
            say!(out, "wrote {}", p.display());
        }
        None => say!(out, "{text}"),
    }
    out.object(&study)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Seed 003 Table 2 (the shipped `restitution_steel.csv`).
    pub(crate) const TABLE2: &str = "# seed 003 Table 2\n\
        impact_angle_deg,type,value,sd\n\
        10,ctr,0.523,0.010\n20,ctr,0.524,0.014\n30,ctr,0.637,0.044\n\
        40,ctr,0.779,0.013\n50,ctr,0.846,0.042\n60,ctr,0.886,0.024\n\
        10,cnr,0.890,0.020\n20,cnr,0.892,0.015\n30,cnr,0.918,0.014\n\
        40,cnr,0.896,0.005\n50,cnr,0.918,0.013\n60,cnr,0.874,0.033\n";

    /// The paper's M1 posterior means (k_t in units of u_E).
    fn paper_m1(mu: f64) -> Vec<f64> {
        vec![mu, 0.81e4, 0.99, 0.0045, 0.0016]
    }

    #[test]
    fn reads_table_2_and_names_bad_cells() {
        let d = parse_csv(TABLE2, "t.csv").unwrap();
        assert_eq!(d.len(), 12);
        assert_eq!(d[0].response, Response::Ctr);
        assert_eq!((d[6].angle_deg, d[6].value, d[6].sd), (10.0, 0.890, 0.020));
        let bad = TABLE2.replace("40,cnr,0.896", "40,cnr,0.8x6");
        let e = parse_csv(&bad, "t.csv").unwrap_err().to_string();
        assert!(
            e.contains("t.csv") && e.contains("line 12, column value"),
            "{e}"
        );
        let e = parse_csv(&TABLE2.replace("20,ctr", "20,ctx"), "t.csv")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("t.csv") && e.contains("line 4, column type"),
            "{e}"
        );
        let e = parse_csv(&TABLE2.replace("0.044", "0"), "t.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 5, column sd"), "{e}");
        let e = parse_csv(&TABLE2.replace(",sd", ",sigma"), "t.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing column `sd`"), "{e}");
        let e = parse_csv(
            &TABLE2.replace("60,cnr,0.874,0.033", "60,cnr,0.874"),
            "t.csv",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("line 14") && e.contains("found 3"), "{e}");
        assert!(parse_csv("# nothing\n", "t.csv").is_err());
        let e = parse_csv(&TABLE2.replace(",sd", ",value"), "t.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("column value") && e.contains("twice"), "{e}");
    }

    #[test]
    fn parameter_layout_follows_the_paper() {
        assert_eq!(NormalModel::M1.parameter_names().len(), 5);
        assert_eq!(NormalModel::M3.parameter_names()[1], "alpha_n");
        let (c, s) = NormalModel::M3.split(&[0.1, 0.44, 5e4, 2.0, 0.004, 0.001], 1e7);
        assert_eq!(
            (c.alpha_n, c.gamma_n, c.k_t, s),
            (0.44, 5e4, 2e7, [0.004, 0.001])
        );
        let (c, _) = NormalModel::M2.split(&paper_m1(0.1), 1.0);
        assert_eq!(c.alpha_n, 0.5);
        let b = NormalModel::M3.prior(&Priors::default());
        assert_eq!(b.lower.len(), 6);
        assert_eq!((b.lower[3], b.upper[3]), (0.1, 15.0));
        assert_eq!(Setup::seed003(E_PRINTED, 2.0).k_t_unit(), 1e7);
    }

    #[test]
    fn likelihood_prefers_the_papers_friction() {
        let data = parse_csv(TABLE2, "t.csv").unwrap();
        // At the printed modulus the paper's k_t (in 1e7 N/m) fits ctr at 10-30 degrees.
        let setup = Setup::seed003(E_PRINTED, DEFAULT_SPEED);
        let like = Likelihood::new(NormalModel::M1, setup.clone(), &data);
        assert_eq!(like.angles.len(), 6);
        let good = like.ln_likelihood(&paper_m1(0.109));
        assert!(good.is_finite(), "{good}");
        for mu in [0.05, 0.2] {
            let wrong = like.ln_likelihood(&paper_m1(mu));
            assert!(
                good > wrong + 20.0,
                "ln L {good} at mu 0.109, {wrong} at mu {mu}"
            );
        }
        // The sliding branch (50-60 deg) of the centre velocity: ctr = 1 - mu (1 + e) / tan.
        let c = like.split(&paper_m1(0.109)).0;
        let (cnr, ctr) = simulate(&setup, &c, 60.0).unwrap();
        let want = 1.0 - 0.109 * (1.0 + cnr) / 60f64.to_radians().tan();
        assert!((ctr - want).abs() < 0.01, "ctr {ctr} vs sliding {want}");
    }

    /// TMCMC on data the DEM generated at a known friction (everything else fixed at the
    /// paper's M1 values) must find that friction: a wrong likelihood, prior mapping or sampler
    /// lands elsewhere in [0.05, 0.2].
    #[test]
    fn tmcmc_recovers_a_known_friction_from_dem_data() {
        let mu_true = 0.16;
        let setup = Setup::seed003(E_PRINTED, DEFAULT_SPEED);
        let fixed = |mu: f64| vec![mu, 0.81e4, 0.99, 0.0, 0.0];
        let truth = NormalModel::M1.split(&fixed(mu_true), setup.k_t_unit()).0;
        // The sliding impacts carry mu; three impacts keep an evaluation cheap.
        let mut data = Vec::new();
        for a in [40.0, 50.0, 60.0] {
            let (cnr, ctr) = simulate(&setup, &truth, a).unwrap();
            for (response, value) in [(Response::Cnr, cnr), (Response::Ctr, ctr)] {
                data.push(ImpactMeasurement {
                    angle_deg: a,
                    response,
                    value,
                    sd: 0.01,
                });
            }
        }
        let like = Likelihood::new(NormalModel::M1, setup, &data);
        let prior = UniformBox {
            lower: vec![0.05],
            upper: vec![0.2],
        };
        let opts = TmcmcOptions {
            samples: 200,
            seed: 7,
            ..TmcmcOptions::default()
        };
        let r = tmcmc(
            &prior,
            |th: &[f64]| like.ln_likelihood(&fixed(th[0])),
            &opts,
        )
        .unwrap();
        let (mean, sd) = (r.mean()[0], r.std()[0]);
        assert!(
            (mean - mu_true).abs() < 0.005 && sd < 0.01,
            "posterior mu {mean} +- {sd}, true {mu_true}"
        );
    }

    #[test]
    fn report_of_a_tiny_run_has_the_table_rows() {
        let data = parse_csv(TABLE2, "t.csv").unwrap();
        let setup = Setup::seed003(E_PRINTED, DEFAULT_SPEED);
        let s = StudySettings {
            samples: 100,
            burn_in: 0,
            replicates: 1,
            youngs_moduli: vec![E_PRINTED],
            classes: vec![NormalModel::M1],
            ..StudySettings::new(100, 1, 0)
        };
        let r = run_class(NormalModel::M1, &setup, &data, &s).unwrap();
        assert!(
            r.evaluations > 100 && r.stages >= 2,
            "{} evaluations, {} stages",
            r.evaluations,
            r.stages
        );
        assert_eq!(r.ln_gamma_alpha_corr, None);
        let study = Study {
            groups: vec![Group {
                setup,
                classes: vec![ClassResult {
                    probability: 1.0,
                    ..r
                }],
                cnr_with_gamma_15: 1.0,
                ctr_with_k_t_1_5e5: 1.0,
                ctr_k_t_sweep: vec![],
            }],
            settings: s,
            ..fake_study(&[], |_, _| {})
        };
        let text = report(&study, "mbgc bench restitution");
        assert!(text.contains("| M1 | mbgc, E = 2.1e10 |"), "{text}");
        assert!(text.contains("Evidence ranking: seed 003 M3 > M2 > M1."));
    }

    /// A class posterior at seed 003's Table 4 means with 10 % sd, three replicate evidences
    /// 0.1 apart, a k_t histogram with the paper's two modes, and (M3) a strong ridge.
    fn fake_class(class: NormalModel) -> ClassResult {
        let row = paper_row(class);
        let mut means = vec![("mu", row.mu.0)];
        if class == NormalModel::M3 {
            means.push(("alpha_n", row.alpha_n.0));
        }
        means.extend([
            ("gamma_n", row.gamma_n.0),
            ("k_t", row.k_t.0),
            ("sigma1_sq", row.sigma1_sq),
            ("sigma2_sq", row.sigma2_sq),
        ]);
        let mut c = ClassResult {
            class,
            parameters: vec![],
            ln_evidence: row.ln_evidence,
            ln_evidence_replicates: vec![
                row.ln_evidence - 0.1,
                row.ln_evidence,
                row.ln_evidence + 0.1,
            ],
            probability: 1.0 / 3.0,
            stages: 5,
            final_acceptance: 0.2,
            evaluations: 1000,
            wall_time_s: 1.0,
            max_ln_likelihood: 30.0,
            best: vec![],
            robust: vec![],
            k_t_histogram: vec![0.0, 0.0, 0.0, 0.3, 0.05, 0.6, 0.05, 0.0, 0.0, 0.0],
            ln_gamma_alpha_corr: (class == NormalModel::M3).then_some(0.9),
        };
        for (n, m) in means {
            c.parameters.push(ParameterSummary {
                name: n.into(),
                mean: 0.0,
                sd: 0.0,
                cov: 0.0,
                q05: 0.0,
                q95: 0.0,
            });
            set(&mut c, n, m);
        }
        c
    }

    /// Sets a parameter's mean, keeping a 10 % sd and a +-1.645 sd interval.
    fn set(c: &mut ClassResult, name: &str, mean: f64) {
        let p = c.parameters.iter_mut().find(|p| p.name == name).unwrap();
        *p = ParameterSummary {
            name: name.into(),
            mean,
            sd: 0.1 * mean,
            cov: 0.1,
            q05: 0.8355 * mean,
            q95: 1.1645 * mean,
        };
    }

    /// A study on Table 2 with one group per modulus, every class from [`fake_class`], then
    /// `edit(modulus, class)`; the literal-reading checks put cnr and ctr far outside the data.
    fn fake_study(moduli: &[f64], edit: impl Fn(f64, &mut ClassResult)) -> Study {
        let data = parse_csv(TABLE2, "t.csv").unwrap();
        let groups = moduli
            .iter()
            .map(|&e| Group {
                setup: Setup::seed003(e, DEFAULT_SPEED),
                classes: NormalModel::ALL
                    .iter()
                    .map(|&cl| {
                        let mut c = fake_class(cl);
                        edit(e, &mut c);
                        c
                    })
                    .collect(),
                cnr_with_gamma_15: 0.999,
                ctr_with_k_t_1_5e5: 0.98,
                ctr_k_t_sweep: vec![[0.1, 0.6], [0.5, 0.5], [1.0, 0.45], [2.0, 0.55]],
            })
            .collect();
        Study {
            data_file: "t.csv".into(),
            data,
            settings: StudySettings::new(100, 1, 1),
            likelihood_ms: 0.3,
            groups,
            speed_groups: vec![],
            wall_time_s: 1.0,
        }
    }

    fn discussion_of(study: &Study) -> String {
        let text = report(study, "test");
        text[text.find("## Discussion").unwrap()..].to_string()
    }

    #[test]
    fn friction_far_from_the_paper_differs_never_agrees() {
        let near = discussion_of(&fake_study(&[E_STEEL], |_, _| {}));
        assert!(near.contains("**Friction mu agrees.**"), "{near}");
        // 0.16 +- 0.016 is 3 sd above the paper's 0.108-0.111.
        let far = discussion_of(&fake_study(&[E_STEEL], |_, c| set(c, "mu", 0.16)));
        assert!(!far.contains("mu agrees"), "{far}");
        assert!(far.contains("**Friction mu differs by up to 3."), "{far}");
    }

    #[test]
    fn gamma_n_verdict_and_the_misprint_follow_the_ratios() {
        let scale = |f: fn(f64) -> f64| {
            move |e: f64, c: &mut ClassResult| {
                let g = param(c, "gamma_n").unwrap().mean;
                set(c, "gamma_n", g * f(e));
            }
        };
        // Off by 0.27 at the printed modulus, exact at steel's: the misprint reading.
        let t = discussion_of(&fake_study(
            &[E_PRINTED, E_STEEL],
            scale(|e| if e == E_PRINTED { 0.27 } else { 1.0 }),
        ));
        assert!(
            t.contains("**gamma_n matches at E = 2.1e11 Pa, not at 2.1e10 Pa.**"),
            "{t}"
        );
        assert!(t.contains("misprint"), "{t}");
        // The other way round: consistent with the printed modulus, no misprint.
        let t = discussion_of(&fake_study(
            &[E_PRINTED, E_STEEL],
            scale(|e| if e == E_STEEL { 3.2 } else { 1.0 }),
        ));
        assert!(
            t.contains("matches at E = 2.1e10 Pa, not at 2.1e11 Pa") && !t.contains("misprint"),
            "{t}"
        );
        // Off everywhere: no match and no misprint.
        let t = discussion_of(&fake_study(&[E_PRINTED, E_STEEL], scale(|_| 4.0)));
        assert!(
            t.contains("**gamma_n matches at no modulus.**") && !t.contains("misprint"),
            "{t}"
        );
        // Matching at both moduli decides nothing about the printed one.
        let t = discussion_of(&fake_study(&[E_PRINTED, E_STEEL], scale(|_| 1.2)));
        assert!(!t.contains("misprint") && !t.contains("not at"), "{t}");
    }

    #[test]
    fn ridge_is_claimed_only_when_the_samples_are_correlated() {
        let t = discussion_of(&fake_study(&[E_STEEL], |_, _| {}));
        assert!(t.contains("ridge is reproduced"), "{t}");
        let t = discussion_of(&fake_study(&[E_STEEL], |_, c| {
            if c.class == NormalModel::M3 {
                c.ln_gamma_alpha_corr = Some(0.2);
            }
        }));
        assert!(
            t.contains("ridge is not reproduced") && !t.contains("ridge is reproduced"),
            "{t}"
        );
    }

    #[test]
    fn bimodality_is_counted_per_run() {
        assert_eq!(mode_bins(&[0.0, 0.3, 0.05, 0.6, 0.05]), vec![1, 3]);
        // A plateau is one mode; a bump under the share threshold is none.
        assert_eq!(mode_bins(&[0.0, 0.45, 0.45, 0.04, 0.06]), vec![1, 4]);
        assert_eq!(mode_bins(&[0.0, 0.45, 0.45, 0.06, 0.04]), vec![1]);
        let t = discussion_of(&fake_study(&[E_STEEL], |_, _| {}));
        assert!(
            t.contains("**k_t: bimodal in every run, as in seed 003"),
            "{t}"
        );
        let t = discussion_of(&fake_study(&[E_STEEL], |_, c| {
            if c.class == NormalModel::M2 {
                c.k_t_histogram = vec![0.0, 0.0, 0.0, 0.0, 0.2, 0.6, 0.2, 0.0, 0.0, 0.0];
            }
        }));
        assert!(
            t.contains("**k_t: bimodal in 2 of 3 runs") && !t.contains("bimodal in every run"),
            "{t}"
        );
    }

    #[test]
    fn evidence_verdicts_follow_the_gaps_and_the_fits() {
        // Table 4's own evidences (replicate sd 0.1): M3 on top, M2 over M1 (0.93 > 2 se).
        let t = discussion_of(&fake_study(&[E_STEEL], |_, _| {}));
        assert!(
            t.contains("**Evidence ranking: M2 over M1 agrees, M3 on top agrees too.**"),
            "{t}"
        );
        // Equal fits, gamma_n 10x apart at equal COV: the lead is prior volume.
        assert!(t.contains("M2 beats M1 on prior volume, not on fit"), "{t}");
        // M2 fitting far better than M1 is a lead on fit, whatever the Occam factors say.
        let t = discussion_of(&fake_study(&[E_STEEL], |_, c| {
            if c.class == NormalModel::M2 {
                c.max_ln_likelihood += 5.0;
            }
        }));
        assert!(
            !t.contains("on prior volume, not on fit") && t.contains("not explained by prior"),
            "{t}"
        );
        // Gaps inside the replicate scatter are not an order.
        let t = discussion_of(&fake_study(&[E_STEEL], |_, c| {
            c.ln_evidence_replicates =
                vec![c.ln_evidence - 3.0, c.ln_evidence, c.ln_evidence + 3.0];
        }));
        assert!(t.contains("M2 over M1 is not resolved"), "{t}");
        // M3 below M2 by many standard errors.
        let t = discussion_of(&fake_study(&[E_STEEL], |_, c| {
            if c.class == NormalModel::M3 {
                c.ln_evidence = 10.0;
                c.ln_evidence_replicates = vec![9.9, 10.0, 10.1];
            }
        }));
        assert!(t.contains("M3 on top does not."), "{t}");
    }

    #[test]
    fn literal_reading_is_confirmed_only_outside_the_measured_range() {
        let t = report(&fake_study(&[E_STEEL], |_, _| {}), "test");
        assert!(t.contains("The DEM confirms it: both"), "{t}");
        let mut s = fake_study(&[E_STEEL], |_, _| {});
        s.groups[0].cnr_with_gamma_15 = 0.9;
        s.groups[0].ctr_with_k_t_1_5e5 = 0.52;
        let t = report(&s, "test");
        assert!(
            t.contains("The DEM does not decide it") && !t.contains("confirms"),
            "{t}"
        );
    }

    #[test]
    fn sweep_crossings_are_interpolated_in_ln_k_t() {
        let g = &fake_study(&[E_STEEL], |_, _| {}).groups[0];
        // Measured ctr at 10 deg is 0.523: crossed between 0.1 and 0.5 and between 1 and 2.
        let x = sweep_crossings(g, &parse_csv(TABLE2, "t.csv").unwrap());
        assert_eq!(x.len(), 2, "{x:?}");
        assert!(
            x[0] > 0.1 && x[0] < 0.5 && x[1] > 1.0 && x[1] < 2.0,
            "{x:?}"
        );
    }

    /// The full M1 calibration on steel's modulus: mu is fixed by the sliding branch (40-60 deg)
    /// whatever the disk/sphere difference, so it must land near the paper's 0.109.
    #[test]
    #[ignore = "about 10 s in release mode"]
    fn m1_posterior_friction_matches_the_sliding_branch() {
        let data = parse_csv(TABLE2, "t.csv").unwrap();
        let s = StudySettings {
            burn_in: 10,
            replicates: 1,
            ..StudySettings::new(2000, 3, 0)
        };
        let r = run_class(NormalModel::M1, &Setup::seed003(E_STEEL, 2.0), &data, &s).unwrap();
        let mu = r.parameters[0].mean;
        eprintln!(
            "M1: mu {mu:.4}, ln Z {:.2}, {} stages",
            r.ln_evidence, r.stages
        );
        assert!((mu - 0.105).abs() < 0.015, "mu {mu}");
        assert!(r.ln_evidence > 5.0, "ln Z {}", r.ln_evidence);
    }
}
