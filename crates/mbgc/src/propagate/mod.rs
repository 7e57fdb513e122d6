//! Propagation: a calibrated posterior carried through DEM to a quantity a plant is designed for
//! (seed 003, Hadjidoukas et al. 2014, section 5: robust predictions from posterior samples).
//!
//! 1. [`PosteriorFile`]: the samples `mbgc calibrate --bayes --posterior-out` wrote.
//! 2. [`resample::systematic`]: n draws from their weights (seeded).
//! 3. [`design`]: one design row per draw and seed for an experiment (a hopper, say), sized to
//!    the material's particles where the experiment has such a setting
//!    ([`crate::experiments::Experiment::sized_to`]). The rows run through the campaign machinery
//!    like any design ([`crate::campaign`]: resumable, shardable).
//! 4. [`Band::of`]: per quantity, the robust mean, sd, 5/50/95 % quantiles and COV over the
//!    draws, and with several seeds per draw the parametric spread apart from the run scatter.
//!    [`EventRate`]: how often a run had an event that leaves it without its responses (a
//!    clogged hopper), with its interval; such runs count as missing in the bands
//!    ([`RecordedRuns`]).
//! 5. [`through_metamodel`]: the same draws through a metamodel of the quantity, when one
//!    exists, with and without its own error: the cheap path beside the DEM band.
//!
//! The DEM is the model of the propagated quantity, so a band from DEM runs carries no model
//! error term: the posterior's `sigma` is the calibration metamodel's relative error and says
//! nothing about the new quantity; it is kept in the file, not added.

pub mod band;
pub mod event_rate;
pub mod metamodel_band;
pub mod posterior_file;
pub mod recorded_runs;
pub mod resample;

pub use band::Band;
pub use event_rate::EventRate;
pub use metamodel_band::{through_metamodel, MetamodelBand};
pub use posterior_file::PosteriorFile;
pub use recorded_runs::RecordedRuns;

use crate::error::{Error, Result};
use crate::experiments::{Experiment, ParamSet};

/// The most seeds one draw runs with.
pub const MAX_SEEDS: usize = 100;

/// The design a propagation runs: `draws.len() * seeds` rows, draw by draw (row r is draw
/// r / seeds). Its seeds are the campaign's per-row seeds, so the replicates of a draw differ
/// only by seed.
#[derive(Debug, Clone, PartialEq)]
pub struct DrawDesign {
    /// The design's columns: the posterior's inputs, then the sizing setting if any.
    pub header: Vec<String>,
    /// One row per run.
    pub rows: Vec<Vec<f64>>,
    /// The posterior sample of each draw.
    pub draws: Vec<usize>,
    /// Runs per draw, each with its own seed.
    pub seeds: usize,
    /// The setting that sizes the experiment to the particles (`scale` of the hopper), if the
    /// design sets it: one value for every draw, the median of what each draw's particles
    /// call for.
    pub sized_by: Option<&'static str>,
}

/// The design that runs `experiment` at the posterior samples `draws`, `seeds` times each.
/// `set` are the constants the command line gives (`--set`): they complete what the posterior
/// lacks. Refused, naming the column or parameter: a posterior input the experiment does not
/// read (it would do nothing), a parameter the experiment needs that neither the posterior nor
/// `set` gives, a constant that is also a posterior input, and 0 or more than [`MAX_SEEDS`]
/// seeds.
pub fn design(
    post: &PosteriorFile,
    experiment: &dyn Experiment,
    draws: &[usize],
    seeds: usize,
    set: &[(String, f64)],
) -> Result<DrawDesign> {
    if seeds == 0 || seeds > MAX_SEEDS {
        return Err(Error::invalid(format!(
            "--seeds {seeds}: expected 1 to {MAX_SEEDS} runs per draw"
        )));
    }
    if draws.len() * seeds > resample::MAX_DRAWS {
        return Err(Error::invalid(format!(
            "--draws {} --seeds {seeds}: {} DEM runs; at most {} in one propagation",
            draws.len(),
            draws.len() * seeds,
            resample::MAX_DRAWS
        )));
    }
    let name = experiment.name();
    let class = experiment
        .class()
        .map(|c| format!(" (model class {c})"))
        .unwrap_or_default();
    let needed = experiment.parameters();
    let optional = experiment.optional_parameters();
    for input in &post.inputs {
        if !needed.contains(&input.as_str()) && !optional.contains(&input.as_str()) {
            return Err(Error::invalid(format!(
                "posterior column {input}: {name}{class} has no parameter {input}, so the \
                 calibrated value would do nothing; propagate to an experiment (and --model-class) \
                 that uses every calibrated parameter"
            )));
        }
    }
    if let Some((k, _)) = set.iter().find(|(k, _)| post.inputs.contains(k)) {
        return Err(Error::invalid(format!(
            "--set {k}: the posterior holds {k} (one value per draw); a constant would replace \
             the calibrated values"
        )));
    }
    let missing: Vec<&str> = needed
        .iter()
        .copied()
        .filter(|n| !post.inputs.iter().any(|i| i == n) && !set.iter().any(|(k, _)| k == n))
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(format!(
            "{name}{class} needs {} that the posterior does not hold; give {} with --set \
             NAME=VALUE",
            missing.join(", "),
            if missing.len() == 1 { "it" } else { "them" }
        )));
    }
    if let Some(&d) = draws.iter().find(|&&d| d >= post.rows.len()) {
        return Err(Error::invalid(format!(
            "draw of sample {d}: the posterior has {} samples",
            post.rows.len()
        )));
    }
    let sizing = |row: &[f64]| {
        let mut p = ParamSet::from_pairs(
            &post
                .inputs
                .iter()
                .cloned()
                .zip(row.iter().copied())
                .collect::<Vec<_>>(),
        );
        for (k, v) in set {
            p.set(k, *v);
        }
        experiment.sized_to(&p)
    };
    // One apparatus for every draw, sized by the median draw: a plant has one orifice, and a
    // size that followed each draw's d50 would mix apparatus sizes into the band. A constant
    // the user set, or a posterior column of that name, wins (the apparatus is then theirs).
    let sizes: Vec<(&'static str, f64)> = draws
        .iter()
        .filter_map(|&d| sizing(&post.rows[d]))
        .collect();
    let sized = sizes
        .first()
        .map(|(k, _)| *k)
        .filter(|k| !set.iter().any(|(s, _)| s == k) && !post.inputs.iter().any(|i| i == k))
        .map(|k| {
            let values: Vec<f64> = sizes.iter().map(|(_, v)| *v).collect();
            (k, crate::numeric::quantile(&values, 0.5))
        });
    let sized_by = sized.map(|(k, _)| k);
    let mut header = post.inputs.clone();
    header.extend(sized_by.map(String::from));
    let mut rows = Vec::with_capacity(draws.len() * seeds);
    for &d in draws {
        let mut row = post.rows[d].clone();
        row.extend(sized.map(|(_, v)| v));
        rows.extend(std::iter::repeat_n(row, seeds));
    }
    Ok(DrawDesign {
        header,
        rows,
        draws: draws.to_vec(),
        seeds,
        sized_by,
    })
}

impl DrawDesign {
    /// The design as CSV text (shortest round-trip numbers, so a resume re-reads the same
    /// values and the same run ids).
    pub fn csv(&self) -> String {
        let mut s = self.header.join(",");
        s.push('\n');
        for r in &self.rows {
            let fields: Vec<String> = r.iter().map(|v| format!("{v:?}")).collect();
            s.push_str(&fields.join(","));
            s.push('\n');
        }
        s
    }

    /// Groups the values of one response, in design-row order (NaN where a run has none), by
    /// draw.
    pub fn by_draw(&self, values: &[f64]) -> Vec<Vec<f64>> {
        values.chunks(self.seeds).map(<[f64]>::to_vec).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::hopper::Hopper;
    use crate::experiments::wall_impact::WallImpact;

    fn posterior(inputs: &[&str], rows: Vec<Vec<f64>>) -> PosteriorFile {
        let n = rows.len();
        PosteriorFile {
            inputs: inputs.iter().map(|s| s.to_string()).collect(),
            rows,
            sigma: vec![0.0; n],
            weights: vec![1.0; n],
            model: "m".into(),
            material: "x".into(),
        }
    }

    const HOPPER: [&str; 12] = [
        "E_p", "E_w", "nu_p", "e_pp", "e_pw", "mu_pp", "mu_pw", "mu_r_pp", "mu_r_pw", "rho_p",
        "d50", "sigma_ln",
    ];

    #[test]
    fn a_hopper_is_sized_to_the_median_draws_particles_and_seeds_repeat_rows() {
        let row = |d50: f64| {
            vec![
                4e7, 4e7, 0.25, 0.6, 0.6, 0.3, 0.36, 0.8, 0.8, 2700.0, d50, 0.26,
            ]
        };
        let post = posterior(&HOPPER, vec![row(11.0), row(4.0), row(6.0)]);
        let d = design(&post, &Hopper::default(), &[2, 0, 1], 2, &[]).unwrap();
        assert_eq!(d.header.last().map(String::as_str), Some("scale"));
        assert_eq!(d.sized_by, Some("scale"));
        assert_eq!(d.rows.len(), 6);
        assert_eq!(d.rows[0], d.rows[1]);
        // One apparatus: the median draw's d50 (6 mm) / 2 mm.
        assert!(
            d.rows.iter().all(|r| r.last() == Some(&3.0)),
            "{:?}",
            d.rows
        );
        assert_eq!(d.rows[2][10], 11.0);
        assert_eq!(
            d.by_draw(&[1.0, 2.0, 3.0, 4.0]),
            [vec![1.0, 2.0], vec![3.0, 4.0]]
        );
        let text = d.csv();
        assert!(
            text.starts_with("E_p,E_w,") && text.lines().count() == 7,
            "{text}"
        );
        // A scale the user sets wins, and is not a design column.
        let set = [("scale".to_string(), 2.0)];
        let d = design(&post, &Hopper::default(), &[0], 1, &set).unwrap();
        assert_eq!((d.sized_by, d.header.len()), (None, 12));
        // So does a posterior that holds it.
        let mut names = HOPPER.to_vec();
        names.push("scale");
        let mut with_scale = row(4.0);
        with_scale.push(2.5);
        let post = posterior(&names, vec![with_scale]);
        let d = design(&post, &Hopper::default(), &[0], 1, &[]).unwrap();
        assert_eq!((d.sized_by, d.header.len()), (None, 13));
        let e = design(&post, &Hopper::default(), &[0; 1001], 100, &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("100100 DEM runs"), "{e}");
    }

    #[test]
    fn what_would_do_nothing_or_is_missing_is_refused_by_name() {
        let post = posterior(&HOPPER, vec![vec![1.0; 12]]);
        // The wall impact has no particle-particle contact: mu_pp would do nothing.
        let e = design(&post, &WallImpact::default(), &[0], 1, &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("posterior column e_pp") && e.contains("wall-impact"),
            "{e}"
        );
        let wall = posterior(
            &[
                "E_p", "nu_p", "rho_p", "d50", "E_w", "e_pw", "mu_pw", "mu_r_pw",
            ],
            vec![vec![1.0; 8]],
        );
        let e = design(&wall, &WallImpact::default(), &[0], 1, &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("impact_speed, impact_angle") && e.contains("--set"),
            "{e}"
        );
        let set = [("mu_pw".to_string(), 0.3)];
        let e = design(&wall, &WallImpact::default(), &[0], 1, &set)
            .unwrap_err()
            .to_string();
        assert!(e.contains("--set mu_pw"), "{e}");
        let set = [
            ("impact_speed".to_string(), 3.0),
            ("impact_angle".to_string(), 30.0),
        ];
        assert!(design(&wall, &WallImpact::default(), &[0], 1, &set).is_ok());
        for seeds in [0, MAX_SEEDS + 1] {
            let e = design(&wall, &WallImpact::default(), &[0], seeds, &set)
                .unwrap_err()
                .to_string();
            assert!(e.contains("--seeds"), "{e}");
        }
        let e = design(&wall, &WallImpact::default(), &[3], 1, &set)
            .unwrap_err()
            .to_string();
        assert!(e.contains("1 samples"), "{e}");
    }
}
