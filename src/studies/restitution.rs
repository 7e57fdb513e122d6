//! Seed 003's restitution study (Hadjidoukas et al. 2014, Sec. 4, Tables 1-4) run directly on DEM
//! impacts: the wall-impact experiment is calibrated by TMCMC to the measured normal and
//! tangential restitution of a steel ball on a steel wall (Table 2) for the three normal-force
//! classes of Table 1, and the classes are ranked by their evidence.
//!
//! - Model classes: `F_n = k_n d^(3/2) + gamma_n d^alpha_n d'` with Hertz's
//!   `k_n = 4/3 Y* sqrt(R*)`, `alpha_n` = 1/4 (M1, Tsuji), 1/2 (M2, Kuwabara-Kono) or free (M3).
//!   Tangential: a constant spring `k_t` with a Coulomb cap `mu F_n` (the wall-impact
//!   experiment's `k_t` override of Mindlin's stiffness), no tangential dashpot (`e_pw = 1`).
//!   The sampled `k_t` is in units of [`Setup::k_t_unit`] (1e7 N/m at the printed modulus,
//!   scaled with the contact time so that both moduli see the same range of tangential period
//!   over contact time); seed 003 does not print its unit.
//! - Parameters, in the paper's order: `(mu, [alpha_n,] gamma_n, k_t, sigma1_sq, sigma2_sq)`, all
//!   with uniform priors ([`Priors`]).
//! - Prediction error (the paper's Eqs. 4-8 and Sec. 4): `measured_r = g_r(theta) + e_r`,
//!   `e_r ~ N(0, sd_r^2 + s_g measured_r^2)` with `s_g = sigma1_sq` for the cnr group and
//!   `sigma2_sq` for the ctr group. The model-error variance scales with the *measured* value
//!   (the paper's `Sigma_m = sigma^2 diag(y_hat^2)`), not with the prediction as in
//!   [`super::bayes`], and the sampled parameters are the variances `sigma^2` themselves (Table 4
//!   prints `sigma1 = 0.0045` where the text says the error is 6.7 % = sqrt(0.0045)).
//! - Each likelihood evaluation runs one DEM impact per measured angle (6 impacts, each giving
//!   cnr and ctr). An impact that does not end (an overdamped ball that stays on the wall) has
//!   zero likelihood.
//!
//! [`run_study`] runs every class for each Young's modulus of the settings (the printed
//! E = 2.1e10 Pa and steel's 2.1e11 Pa, because the paper's posterior only makes sense with the
//! latter, see the report), and [`report`] writes the comparison with seed 003 Table 4.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::calibrate::bayes::class_probabilities;
use crate::calibrate::tmcmc::{tmcmc, TmcmcOptions, TmcmcResult, UniformBox};
use crate::dem::contact::NormalKind;
use crate::dem::experiments::wall_impact::WallImpact;
use crate::dem::experiments::{Experiment, ParamSet, RunOptions};
use crate::error::{csv_error, csv_number, csv_open_str, write_atomic, Error, Result};

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
pub struct Measurement {
    /// Impact angle from the wall normal, degrees.
    pub angle_deg: f64,
    pub response: Response,
    pub value: f64,
    pub sd: f64,
}

const COLUMNS: [&str; 4] = ["impact_angle_deg", "type", "value", "sd"];

/// Reads the measurements (`impact_angle_deg,type,value,sd`; `#` lines are comments).
pub fn load_csv(path: &Path) -> Result<Vec<Measurement>> {
    let text = crate::error::read_to_string(path)?;
    parse_csv(&text, &path.display().to_string())
}

/// Parses the measurement table with the shared CSV reader; errors name `file`, the line and
/// the column. The columns may come in any order; each must appear once.
pub fn parse_csv(text: &str, file: &str) -> Result<Vec<Measurement>> {
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
        out.push(Measurement {
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

    /// Hertz constant k_n = 4/3 Y* sqrt(R*) against a wall of the same material, N/m^1.5.
    pub fn k_n(&self) -> f64 {
        let y_eff = self.youngs_modulus / (2.0 * (1.0 - self.poisson * self.poisson));
        4.0 / 3.0 * y_eff * self.radius.sqrt()
    }
}

/// The normal-force classes of seed 003 Table 1.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ModelClass {
    /// Tsuji: damping gamma_n d^(1/4) d'.
    M1,
    /// Kuwabara-Kono: gamma_n d^(1/2) d'.
    M2,
    /// Free exponent: gamma_n d^alpha_n d'.
    M3,
}

impl ModelClass {
    pub const ALL: [ModelClass; 3] = [ModelClass::M1, ModelClass::M2, ModelClass::M3];

    pub fn label(self) -> &'static str {
        match self {
            ModelClass::M1 => "M1",
            ModelClass::M2 => "M2",
            ModelClass::M3 => "M3",
        }
    }

    pub fn description(self) -> &'static str {
        match self {
            ModelClass::M1 => "Tsuji, alpha_n = 1/4",
            ModelClass::M2 => "Kuwabara-Kono, alpha_n = 1/2",
            ModelClass::M3 => "free alpha_n",
        }
    }

    /// Fixed damping exponent, `None` for M3.
    pub fn fixed_alpha(self) -> Option<f64> {
        match self {
            ModelClass::M1 => Some(0.25),
            ModelClass::M2 => Some(0.5),
            ModelClass::M3 => None,
        }
    }

    /// Parameter names in the paper's order.
    pub fn parameter_names(self) -> Vec<&'static str> {
        let mut v = vec!["mu"];
        if self == ModelClass::M3 {
            v.push("alpha_n");
        }
        v.extend(["gamma_n", "k_t", "sigma1_sq", "sigma2_sq"]);
        v
    }

    /// The uniform prior of the class.
    pub fn prior(self, p: &Priors) -> UniformBox {
        let mut b = vec![p.mu];
        if self == ModelClass::M3 {
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
        // No tangential dashpot: e_pw = 1 gives beta = 0 (normal damping is gamma_n's).
        ("e_pw", 1.0),
        ("mu_pw", c.mu),
        ("impact_speed", setup.impact_speed),
        ("impact_angle", angle_deg),
        ("gamma_n", c.gamma_n),
        ("k_t", c.k_t),
    ]);
    let exp = WallImpact {
        normal: NormalKind::PowerDamped { alpha: c.alpha_n },
    };
    let o = exp.run(&p, 0, &RunOptions::default())?;
    let get = |k: &str| o.get(k).unwrap_or(f64::NAN);
    Ok((get("cnr"), get("ctr")))
}

/// The likelihood of one model class on one setup.
#[derive(Clone, Debug)]
pub struct Likelihood<'a> {
    pub class: ModelClass,
    pub setup: Setup,
    pub data: &'a [Measurement],
    /// Distinct impact angles, ascending; one impact each.
    pub angles: Vec<f64>,
    /// Index into `angles` of each measurement.
    index: Vec<usize>,
}

impl<'a> Likelihood<'a> {
    pub fn new(class: ModelClass, setup: Setup, data: &'a [Measurement]) -> Self {
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
    pub classes: Vec<ModelClass>,
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
            classes: ModelClass::ALL.to_vec(),
        }
    }
}

/// Posterior summary of one parameter.
pub use crate::calibrate::bayes::Summary as ParameterSummary;

/// Posterior of one class on one setup.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassResult {
    pub class: ModelClass,
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

/// All classes on one setup.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Group {
    pub setup: Setup,
    pub classes: Vec<ClassResult>,
    /// What the literal (SI) reading of Table 3 would give, at the M1 posterior mean: mean cnr
    /// with gamma_n = 15, and ctr at the smallest angle with k_t = 1.5e5 N/m.
    pub cnr_with_gamma_15: f64,
    pub ctr_with_k_t_1_5e5: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Study {
    pub data_file: String,
    pub data: Vec<Measurement>,
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
pub fn run_on(data: &[Measurement], s: &StudySettings, log: impl Fn(&str) + Sync) -> Result<Study> {
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
            ModelClass::M1,
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
    data: &[Measurement],
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
    Ok(Group {
        setup: setup.clone(),
        cnr_with_gamma_15: cnr.iter().sum::<f64>() / cnr.len().max(1) as f64,
        ctr_with_k_t_1_5e5: simulate(setup, &lit_kt, amin).map_or(f64::NAN, |r| r.1),
        classes,
    })
}

/// TMCMC of one class on one setup (in the current rayon pool).
pub fn run_class(
    class: ModelClass,
    setup: &Setup,
    data: &[Measurement],
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
    class: ModelClass,
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
    }
}

/// One row of seed 003 Table 4 (gamma_n in N s/m^(1+alpha), k_t in the paper's unprinted unit,
/// sigma's as printed, i.e. variances).
#[derive(Clone, Copy, Debug)]
pub struct PaperRow {
    pub class: ModelClass,
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
        class: ModelClass::M1,
        mu: (0.109, 0.128),
        alpha_n: (0.25, None),
        gamma_n: (0.81e4, 0.172),
        k_t: (0.99, 0.351),
        sigma1_sq: 0.0045,
        sigma2_sq: 0.0016,
        ln_evidence: 15.46,
    },
    PaperRow {
        class: ModelClass::M2,
        mu: (0.108, 0.1177),
        alpha_n: (0.5, None),
        gamma_n: (8.41e4, 0.187),
        k_t: (1.01, 0.338),
        sigma1_sq: 0.0035,
        sigma2_sq: 0.0019,
        ln_evidence: 16.39,
    },
    PaperRow {
        class: ModelClass::M3,
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

fn ranking(ln_z: &[(ModelClass, f64)]) -> String {
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
    let _ =
        writeln!(
        w,
        "- Table 3 lists the priors as mu x gamma_n [0.1, 15] x k_t [0.1e4, 15e4], Table 4 prints \
         gamma_n = 0.81e4 / 8.41e4 / 5.45e4 and k_t = 0.99 / 1.01 / 1.04, and the text agrees with \
         Table 4 (gamma_n COV 17.2 % in M1, \"MAP 8.41 for M2 compared to 0.81 for M1\", k_t modes \
         at 0.4 and 1.33, gamma_n of M3 spread over \"0.1 to 15\"). So gamma_n lives on \
         [0.1, 15] x 1e4 and k_t on [0.1, 15] in some unit; Table 3's two columns are swapped. The \
         DEM confirms it: with the literal reading the M1 posterior mean with gamma_n = 15 gives a \
         mean cnr of {} (measured 0.87-0.92), and k_t = 1.5e5 N/m gives ctr = {} at the smallest \
         angle (measured 0.52): a spring that soft does not act within one ~0.1 ms impact.",
        study
            .groups
            .iter()
            .map(|g| format!("{:.4} (E = {:.1e})", g.cnr_with_gamma_15, g.setup.youngs_modulus))
            .collect::<Vec<_>>()
            .join(" / "),
        study
            .groups
            .iter()
            .map(|g| format!("{:.3} (E = {:.1e})", g.ctr_with_k_t_1_5e5, g.setup.youngs_modulus))
            .collect::<Vec<_>>()
            .join(" / ")
    );
    let _ = writeln!(
        w,
        "- k_t's unit is not printed. mbgc samples k_t on [0.1, 15] in units of u_E = 1e7 N/m at \
         E = 2.1e10 Pa, the band where a linear spring changes ctr at 10-30 degrees for this ball \
         (a spring acts when its period is comparable with the ~0.1-0.3 ms contact), scaled as \
         E^0.8 like 1/t_c^2 so that both moduli sample the same range of period over contact \
         time; the width ratio 150 is the paper's, so the Occam factors are comparable. The k_t \
         columns are compared in shape (modes, COV) more than in value."
    );
    let _ = writeln!(
        w,
        "- sigma1, sigma2 of Table 4 (0.0045, 0.0016 in M1) are variances: the text calls them \
         prediction errors of 6.7 % and 4.0 %, i.e. their square roots. Here too the sampled \
         parameters are sigma^2 with the prior [0, 0.01], and sigma1 belongs to cnr, sigma2 to \
         ctr (Sec. 4: Sigma_cnr = sigma1^2 diag(y_cnr^2)).\n"
    );
    discussion(study, w);
    o
}

fn range_of(values: impl Iterator<Item = f64>) -> (f64, f64) {
    values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    })
}

/// Modes of a histogram: bins larger than both neighbours (and 5 % of the mass), as
/// "lo-hi (share)".
fn modes(h: &[f64], edges: &[f64]) -> Vec<String> {
    (0..h.len())
        .filter(|&k| {
            h[k] >= 0.05 && (k == 0 || h[k] > h[k - 1]) && (k + 1 == h.len() || h[k] >= h[k + 1])
        })
        .map(|k| {
            format!(
                "{:.2}-{:.2} ({:.0} %)",
                edges[k],
                edges[k + 1],
                100.0 * h[k]
            )
        })
        .collect()
}

/// The discussion: what agrees with seed 003 and what does not, with the numbers of the run.
fn discussion(study: &Study, w: &mut String) {
    let s = &study.settings;
    let _ = writeln!(w, "## Discussion: what agrees, what does not, and why\n");
    let all: Vec<(&Group, &ClassResult)> = study
        .groups
        .iter()
        .flat_map(|g| g.classes.iter().map(move |c| (g, c)))
        .collect();
    let mean_of = |c: &ClassResult, n: &str| param(c, n).map_or(f64::NAN, |p| p.mean);
    let paper = |c: ModelClass| PAPER_TABLE4.iter().find(|r| r.class == c);

    // Friction.
    let (lo, hi) = range_of(all.iter().map(|(_, c)| mean_of(c, "mu")));
    let (plo, phi) = range_of(PAPER_TABLE4.iter().map(|r| r.mu.0));
    let (clo, chi) = range_of(
        all.iter()
            .map(|(_, c)| param(c, "mu").map_or(f64::NAN, |p| p.cov)),
    );
    let mu_ours = 0.5 * (lo + hi);
    let shift = (mu_ours - 0.5 * (plo + phi)) / (mu_ours * 0.5 * (clo + chi));
    let _ = writeln!(
        w,
        "**Friction mu agrees.** Posterior means {lo:.3}-{hi:.3} in every class and modulus \
         (COV {:.0}-{:.0} %) against seed 003's {plo:.3}-{phi:.3} (COV 9.5-12.8 %): {:.0} % {}, \
         {:.1} posterior sd. mu is set by the impacts that slide throughout the contact (40-60 \
         deg here): there the centre velocity obeys ctr = 1 - mu (1 + cnr) / tan(theta), which \
         depends neither on the moment of inertia (sphere 2/5 m R^2, disk 1/2 m R^2) nor on the \
         stiffnesses, so the 2-D disk and the 3-D sphere read the same mu off the same data. \
         Impacts with tan(theta) < mu (1 + e) (1 + m R^2 / I) end up sticking (rigid-body \
         theory): below about {:.0} deg for the sphere and {:.0} deg for the disk, so 30 deg is a \
         stick-slip impact for both and informs mu less.\n",
        100.0 * clo,
        100.0 * chi,
        100.0 * (mu_ours / (0.5 * (plo + phi)) - 1.0).abs(),
        if mu_ours < 0.5 * (plo + phi) {
            "lower"
        } else {
            "higher"
        },
        shift.abs(),
        (mu_ours * 1.9 * 3.5).atan().to_degrees(),
        (mu_ours * 1.9 * 3.0).atan().to_degrees(),
    );

    // gamma_n.
    let mut lines = Vec::new();
    let mut best_e = (f64::NAN, f64::INFINITY);
    for g in &study.groups {
        let ratios: Vec<(ModelClass, f64)> = g
            .classes
            .iter()
            .filter(|c| c.class != ModelClass::M3)
            .filter_map(|c| paper(c.class).map(|p| (c.class, mean_of(c, "gamma_n") / p.gamma_n.0)))
            .collect();
        if ratios.is_empty() {
            continue;
        }
        let miss = ratios.iter().map(|r| r.1.ln().abs()).sum::<f64>() / ratios.len() as f64;
        if miss < best_e.1 {
            best_e = (g.setup.youngs_modulus, miss);
        }
        lines.push(format!(
            "at E = {:.1e} Pa {}",
            g.setup.youngs_modulus,
            ratios
                .iter()
                .map(|(c, r)| format!("{} {r:.2}", c.label()))
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if !lines.is_empty() {
        let _ = writeln!(
            w,
            "**gamma_n matches at E = {:.1e} Pa.** Both codes use the same normal law: seed 003 \
             takes the 3-D Hertz constant k_n = 4/3 E* sqrt(R*) even for its disks (Sec. 2), with \
             the measured ball's mass, and its gamma_n multiplies d^alpha_n d' in \
             N s/m^(1+alpha_n) exactly as mbgc's `gamma_n` does, so the values compare directly \
             once E is the same. Ratios mbgc / seed 003 of the posterior means: {}. For a given \
             restitution gamma_n scales as sqrt(k_n m) ~ E^(1/2) in M1 (Tsuji's damping is \
             speed-independent), a factor 3.2 between the two moduli. {} The mass is the same in \
             both (the sphere's density is set to give 0.3538 kg; the measured ball, 44.5 mm of \
             steel, weighs about that), so it is not a source of difference.\n",
            best_e.0,
            lines.join("; "),
            if best_e.0 == E_STEEL {
                "Seed 003's gamma_n values therefore belong to steel's E = 2.1e11 Pa, not to the \
                 printed 2.10e10: the printed modulus is most likely a misprint (or not what its \
                 code ran)."
            } else {
                "Seed 003's gamma_n values are consistent with the modulus it prints."
            }
        );
    }

    // alpha_n and the ridge.
    let m3: Vec<String> = all
        .iter()
        .filter(|(_, c)| c.class == ModelClass::M3)
        .map(|(g, c)| {
            let a = param(c, "alpha_n");
            format!(
                "{:.2} (COV {:.0} %, 5-95 % {:.2}-{:.2}; gamma_n COV {:.0} %) at E = {:.1e}",
                a.map_or(f64::NAN, |p| p.mean),
                100.0 * a.map_or(f64::NAN, |p| p.cov),
                a.map_or(f64::NAN, |p| p.q05),
                a.map_or(f64::NAN, |p| p.q95),
                100.0 * param(c, "gamma_n").map_or(f64::NAN, |p| p.cov),
                g.setup.youngs_modulus,
            )
        })
        .collect();
    if !m3.is_empty() {
        let _ = writeln!(
            w,
            "**M3: the (gamma_n, alpha_n) ridge is reproduced, the exponent less sharply.** mbgc \
             finds alpha_n = {} against seed 003's 0.44 (COV 5.8 %; gamma_n COV 55.5 %). As in \
             the paper, gamma_n and alpha_n trade off along a ridge (with d < 1 mm a larger \
             exponent needs a larger gamma_n for the same dissipation), so gamma_n is not \
             identified, and the mean of M3's parameters is not itself a good fit: use the \
             robust predictions.\n",
            m3.join("; ")
        );
    }

    // k_t.
    let edges: Vec<f64> = (0..=K_T_BINS)
        .map(|k| {
            let (lo, hi) = (s.priors.k_t[0].ln(), s.priors.k_t[1].ln());
            (lo + (hi - lo) * k as f64 / K_T_BINS as f64).exp()
        })
        .collect();
    let kt: Vec<String> = all
        .iter()
        .map(|(g, c)| {
            let m = modes(&c.k_t_histogram, &edges);
            format!(
                "{} at E = {:.1e}: {}",
                c.class.label(),
                g.setup.youngs_modulus,
                if m.is_empty() {
                    "none".into()
                } else {
                    m.join(" and ")
                }
            )
        })
        .collect();
    let _ = writeln!(
        w,
        "**k_t: the same bimodality, in units that cannot be compared.** Seed 003 reports a \
         bimodal k_t posterior in every class, modes at 0.4 and 1.33 with the upper one about \
         twice as probable. mbgc's modes (log-spaced bins in u_E, with their posterior share): \
         {}. The mechanism is the same in both codes: at 10-20 deg the contact point sticks and \
         the tangential spring, loaded during the contact, throws it back; how far depends on the \
         spring's period against the contact time, ctr(10 deg) first falls and then rises with \
         k_t, and two stiffnesses give the measured 0.52 (the paper blames the missing data below \
         10 deg, which is the same statement). Values \
         differ for reasons of dimension: the tangential effective mass m / (1 + m R^2 / I) is \
         2/7 m for the sphere and 1/3 m for the disk (a 14 % softer spring gives the sphere the \
         same period), the rigid-rolling ctr is 5/7 against 2/3, and k_t's unit is unknown.\n",
        kt.join("; ")
    );

    // sigmas and where ctr misses.
    let (s1lo, s1hi) = range_of(all.iter().map(|(_, c)| mean_of(c, "sigma1_sq")));
    let (s2lo, s2hi) = range_of(all.iter().map(|(_, c)| mean_of(c, "sigma2_sq")));
    let worst: Vec<String> = study
        .groups
        .last()
        .and_then(|g| {
            g.classes
                .iter()
                .max_by(|a, b| a.ln_evidence.total_cmp(&b.ln_evidence))
        })
        .map(|c| {
            let mut z: Vec<(f64, f64, f64, f64)> = c
                .robust
                .iter()
                .filter_map(|p| {
                    study
                        .data
                        .iter()
                        .find(|m| m.angle_deg == p.angle_deg && m.response == Response::Ctr)
                        .map(|m| (p.angle_deg, p.ctr[0], m.value, (p.ctr[0] - m.value) / m.sd))
                })
                .collect();
            z.sort_by(|a, b| b.3.abs().total_cmp(&a.3.abs()));
            z.iter()
                .take(2)
                .map(|(a, g, y, z)| format!("{a} deg {g:.3} against {y:.3} ({z:+.1} sd)"))
                .collect()
        })
        .unwrap_or_default();
    let cnr_data: Vec<&Measurement> = study
        .data
        .iter()
        .filter(|m| m.response == Response::Cnr)
        .collect();
    let e_mean = cnr_data.iter().map(|m| m.value).sum::<f64>() / cnr_data.len().max(1) as f64;
    let sliding: Vec<String> = study
        .data
        .iter()
        .filter(|m| {
            m.response == Response::Ctr
                && m.angle_deg.to_radians().tan() > mu_ours * (1.0 + e_mean) * 3.5
        })
        .map(|m| {
            format!(
                "{:.3} at {} deg",
                (1.0 - m.value) * m.angle_deg.to_radians().tan() / (1.0 + e_mean),
                m.angle_deg
            )
        })
        .collect();
    let _ = writeln!(
        w,
        "**Model-error variances.** mbgc: sigma1^2 (cnr) {s1lo:.4}-{s1hi:.4}, sigma2^2 (ctr) \
         {s2lo:.4}-{s2hi:.4}; seed 003: 0.0035-0.0045 and 0.0007-0.0019. Both posteriors are \
         wide (COV around 100 %: twelve points say little about two variances). The sphere's \
         cnr, nearly flat over the angles, sits inside the scatter of the measured cnr; its \
         largest ctr misses (robust mean, most probable class, last modulus) are {}. Around 30 \
         deg the sphere's stick-slip impacts return more tangential velocity than the disk's \
         (rigid-rolling limit 5/7 against 2/3), and the sliding impacts want slightly \
         different mu each ({} from ctr = 1 - mu (1 + {:.3}) / tan(theta) with the mean \
         measured cnr), which only the ctr model error can absorb.\n",
        worst.join(", "),
        sliding.join(", "),
        e_mean
    );

    // Evidence.
    let paper_rank = ranking(&PAPER_TABLE4.map(|r| (r.class, r.ln_evidence)));
    let occam = |c: &ClassResult| {
        param(c, "gamma_n").map_or(f64::NAN, |p| {
            ((2.0 * std::f64::consts::PI).sqrt() * p.sd
                / (s.priors.gamma_n[1] - s.priors.gamma_n[0]))
                .ln()
        })
    };
    let mut ev = Vec::new();
    for g in &study.groups {
        let get = |cl: ModelClass| g.classes.iter().find(|c| c.class == cl);
        let r = ranking(
            &g.classes
                .iter()
                .map(|c| (c.class, c.ln_evidence))
                .collect::<Vec<_>>(),
        );
        let mut t = format!("at E = {:.1e} Pa the order is {r}", g.setup.youngs_modulus);
        if let (Some(m1), Some(m2)) = (get(ModelClass::M1), get(ModelClass::M2)) {
            let _ = write!(
                t,
                "; M2 - M1 = {:.2} in ln evidence while their best fits differ by {:.2} in ln L \
                 and the gamma_n Occam factors ln(sqrt(2 pi) sd / prior width) by {:.2}",
                m2.ln_evidence - m1.ln_evidence,
                m2.max_ln_likelihood - m1.max_ln_likelihood,
                occam(m2) - occam(m1)
            );
        }
        if let Some(m3) = get(ModelClass::M3) {
            let b12 = g
                .classes
                .iter()
                .filter(|c| c.class != ModelClass::M3)
                .map(|c| c.max_ln_likelihood)
                .fold(f64::NEG_INFINITY, f64::max);
            let _ = write!(
                t,
                "; M3's best fit is {:.2} in ln L above the better of M1 and M2",
                m3.max_ln_likelihood - b12
            );
        }
        ev.push(t);
    }
    let z_of = |g: &Group, cl: ModelClass| {
        g.classes
            .iter()
            .find(|c| c.class == cl)
            .map_or(f64::NAN, |c| c.ln_evidence)
    };
    let m2_over_m1 = study
        .groups
        .iter()
        .all(|g| z_of(g, ModelClass::M2) > z_of(g, ModelClass::M1));
    let m3_top = study.groups.iter().all(|g| {
        g.classes
            .iter()
            .all(|c| c.class == ModelClass::M3 || c.ln_evidence < z_of(g, ModelClass::M3))
    });
    let (zlo, zhi) = range_of(all.iter().map(|(_, c)| c.ln_evidence));
    // Correlation of the measured cnr with the normal impact speed (cos theta).
    let corr = {
        let xs: Vec<f64> = cnr_data
            .iter()
            .map(|m| m.angle_deg.to_radians().cos())
            .collect();
        let ys: Vec<f64> = cnr_data.iter().map(|m| m.value).collect();
        let n = xs.len() as f64;
        let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
        let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
        let sxx: f64 = xs.iter().map(|x| (x - mx).powi(2)).sum();
        let syy: f64 = ys.iter().map(|y| (y - my).powi(2)).sum();
        sxy / (sxx * syy).sqrt()
    };
    let (ylo, yhi) = range_of(cnr_data.iter().map(|m| m.value));
    let _ = writeln!(
        w,
        "**Evidence ranking: M2 over M1 {}, M3 on top {}.** Seed 003 finds \
         {paper_rank} with ln evidence 22.41, 16.39 and 15.46 (M3 probability 0.997, M2 ahead of \
         M1 by 0.93). In mbgc {}. mbgc's log-evidences ({zlo:.1}-{zhi:.1}) are of the paper's \
         size, so the likelihoods are comparable. M2 beats M1 on prior volume, not on fit: both share the \
         gamma_n prior [{:.1e}, {:.1e}], and M1's gamma_n (Tsuji) needs a ten times smaller value \
         for the same restitution, so it occupies a smaller share of that prior (with the paper's \
         gamma_n COVs, 17 % and 19 %, the same estimate gives its M2 a 2.4 advantage; its \
         smaller gap of 0.93 implies that its M1 fits somewhat better than its M2). M3 contains M1 and M2 (alpha_n = 1/4, 1/2), so its best fit cannot be \
         worse, but on the sphere the free exponent buys almost nothing: alpha_n can only shape \
         the trend of cnr with the normal speed v cos(theta) (1 - e grows as \
         v_n^((4 alpha_n - 1)/5)), and the measured cnr ({ylo:.3}-{yhi:.3}) barely follows v_n \
         (correlation with cos(theta) {corr:+.2}), so the extra dimension mostly costs its Occam \
         factor (alpha_n's posterior spans a fraction of [{}, {}]). \
         Seed 003's M3 gains six units, and its sigma2^2 drops from 0.0016 to 0.0007, so its M3 \
         fits ctr better than its M1: in the disk model the damping exponent evidently changes \
         the stick-slip impacts more than in the sphere; the paper shows no per-angle predictions \
         that would let us locate that gain. Single TMCMC runs scatter: the replicate sd is in \
         the tables above (largest for {}); with 10 instead of 40 burn-in steps \
         single M1 runs spread over 16.5-19.1 (2000 samples, E = 2.1e11, three seeds; measured \
         separately with this code).\n",
        if m2_over_m1 { "agrees" } else { "does not hold everywhere" },
        if m3_top { "agrees too" } else { "does not" },
        ev.join("; "),
        s.priors.gamma_n[0],
        s.priors.gamma_n[1],
        s.priors.alpha_n[0],
        s.priors.alpha_n[1],
        all.iter()
            .max_by(|a, b| ln_z_sd(a.1).total_cmp(&ln_z_sd(b.1)))
            .map_or("-".into(), |(g, c)| format!(
                "{} at E = {:.1e}, sd {:.2}",
                c.class.label(),
                g.setup.youngs_modulus,
                ln_z_sd(c)
            ))
    );

    // Speed and smaller differences.
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
        let (mlo, mhi) = range_of(
            rows.iter()
                .flat_map(|g| g.classes.iter().map(|c| mean_of(c, "mu"))),
        );
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
        let kt: Vec<String> = rows
            .iter()
            .filter_map(|g| {
                g.classes.first().and_then(|c| {
                    param(c, "k_t").map(|p| {
                        format!(
                            "{:.2e} N/m at {} m/s",
                            p.mean * g.setup.k_t_unit(),
                            g.setup.impact_speed
                        )
                    })
                })
            })
            .collect();
        sp = format!(
            "Recalibrated at other speeds (E = {e:.1e} Pa), mu stays within {mlo:.3}-{mhi:.3}, \
             the ranking reads {}, and the M1 k_t mean moves {} (a fixed spring's effect goes \
             with the contact time t_c ~ v^(-1/5)): the k_t values are tied to the assumed \
             speed, mu is not. ",
            ranks.join(", "),
            kt.join(", ")
        );
    }
    let _ = writeln!(
        w,
        "**Unknowns and smaller differences.** The impact speed is not in seed 003. {sp}The wall \
         is a flat plane here and a phantom disk of very small curvature there (both R* = R). \
         Seed 003 integrates with a third-order Gear predictor-corrector at 1e-6 s, mbgc with \
         velocity Verlet at 1/400 of the Hertz contact time. At the Coulomb cap seed 003 stops \
         integrating the spring (the Heaviside in its Eq. 3) while mbgc resets it to \
         mu F_n / k_t (LIGGGHTS' rule); neither has a tangential dashpot. A likelihood \
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
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Measured restitution, columns impact_angle_deg,type,value,sd (seed 003 Table 2:
    /// examples/restitution_steel.csv).
    #[arg(long)]
    pub data: PathBuf,
    /// TMCMC samples per stage.
    #[arg(long, default_value_t = 2000)]
    pub samples: usize,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Threads (0: all cores); the result does not depend on it.
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// Metropolis steps per chain and stage before the recorded one.
    #[arg(long, default_value_t = 40)]
    pub burn_in: usize,
    /// Independent TMCMC runs per class (seeds seed, seed+1, ...): evidence scatter.
    #[arg(long, default_value_t = 3)]
    pub replicates: usize,
    /// Young's moduli of particle and wall, Pa, one group of runs each (comma-separated).
    #[arg(long, value_delimiter = ',', default_values_t = [2.1e10, 2.1e11])]
    pub youngs: Vec<f64>,
    /// Impact speed, m/s (seed 003 does not state it).
    #[arg(long, default_value_t = 2.0)]
    pub speed: f64,
    /// Other speeds at which every class is recalibrated on the last modulus (one run each);
    /// give the flag without values to skip.
    #[arg(long, value_delimiter = ',', num_args = 0.., default_values_t = [1.0, 4.0])]
    pub speed_check: Vec<f64>,
    /// Markdown report (e.g. docs/bayes_restitution.md).
    #[arg(long)]
    pub report: Option<PathBuf>,
}

pub fn run(a: &Args) -> anyhow::Result<()> {
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
    match &a.report {
        Some(p) => {
            write_atomic(p, text.as_bytes())?;
            println!("wrote {}", p.display());
        }
        None => print!("{text}"),
    }
    Ok(())
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
        assert_eq!(ModelClass::M1.parameter_names().len(), 5);
        assert_eq!(ModelClass::M3.parameter_names()[1], "alpha_n");
        let (c, s) = ModelClass::M3.split(&[0.1, 0.44, 5e4, 2.0, 0.004, 0.001], 1e7);
        assert_eq!(
            (c.alpha_n, c.gamma_n, c.k_t, s),
            (0.44, 5e4, 2e7, [0.004, 0.001])
        );
        let (c, _) = ModelClass::M2.split(&paper_m1(0.1), 1.0);
        assert_eq!(c.alpha_n, 0.5);
        let b = ModelClass::M3.prior(&Priors::default());
        assert_eq!(b.lower.len(), 6);
        assert_eq!((b.lower[3], b.upper[3]), (0.1, 15.0));
        assert_eq!(Setup::seed003(E_PRINTED, 2.0).k_t_unit(), 1e7);
    }

    #[test]
    fn likelihood_prefers_the_papers_friction_and_a_tiny_tmcmc_runs() {
        let data = parse_csv(TABLE2, "t.csv").unwrap();
        // At the printed modulus the paper's k_t (in 1e7 N/m) fits ctr at 10-30 degrees.
        let setup = Setup::seed003(E_PRINTED, DEFAULT_SPEED);
        let like = Likelihood::new(ModelClass::M1, setup.clone(), &data);
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

        let s = StudySettings {
            samples: 200,
            burn_in: 0,
            replicates: 1,
            youngs_moduli: vec![E_PRINTED],
            classes: vec![ModelClass::M1],
            ..StudySettings::new(200, 1, 0)
        };
        let r = run_class(ModelClass::M1, &setup, &data, &s).unwrap();
        assert!(r.ln_evidence.is_finite());
        let mu = &r.parameters[0];
        assert!(mu.mean > 0.05 && mu.mean < 0.2 && mu.q05 <= mu.q95);
        assert!(
            r.evaluations > 200 && r.stages >= 2,
            "{} evaluations, {} stages",
            r.evaluations,
            r.stages
        );
        let study = Study {
            data_file: "t.csv".into(),
            data: data.clone(),
            settings: s,
            likelihood_ms: 0.3,
            groups: vec![Group {
                setup,
                classes: vec![ClassResult {
                    probability: 1.0,
                    ..r
                }],
                cnr_with_gamma_15: 1.0,
                ctr_with_k_t_1_5e5: 1.0,
            }],
            speed_groups: vec![],
            wall_time_s: 1.0,
        };
        let text = report(&study, "mbgc bench restitution");
        assert!(text.contains("| M1 | mbgc, E = 2.1e10 |"), "{text}");
        assert!(text.contains("Evidence ranking: seed 003 M3 > M2 > M1."));
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
        let r = run_class(ModelClass::M1, &Setup::seed003(E_STEEL, 2.0), &data, &s).unwrap();
        let mu = r.parameters[0].mean;
        eprintln!(
            "M1: mu {mu:.4}, ln Z {:.2}, {} stages",
            r.ln_evidence, r.stages
        );
        assert!((mu - 0.105).abs() < 0.015, "mu {mu}");
        assert!(r.ln_evidence > 5.0, "ln Z {}", r.ln_evidence);
    }
}
