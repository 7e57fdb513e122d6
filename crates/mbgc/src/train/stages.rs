//! The stages' building blocks: where a train's files go, the seeds of its random streams, the
//! designs it creates or extends, the plan of each campaign, the fit's inputs and the record
//! written beside the tables.

use std::path::{Path, PathBuf};

use crate::campaign::{ExperimentSettings, Plan, Shard};
use crate::error::{Error, Result};
use crate::experiments::Experiment;
use crate::sampling::design::Design;
use crate::sampling::{extend_design, fssf, random, Sampler};
use crate::space::Space;

/// The files of a trained metamodel named `name` under `dir`.
#[derive(Debug, Clone)]
pub struct TrainPaths {
    /// `sampling/<name>.csv`: the training design (FSSF-f, extended in place).
    pub design: PathBuf,
    /// `sampling/<name>_validation.csv`: the random validation design.
    pub validation_design: PathBuf,
    /// `training_data/<name>.csv`: the campaign table of the training runs.
    pub table: PathBuf,
    /// `training_data/<name>_validation.csv`: the campaign table of the validation runs.
    pub validation_table: PathBuf,
    /// `training_data/<name>.train.json`: the [`TrainRecord`].
    pub record: PathBuf,
    /// `models/<name>.json`: the fitted metamodel.
    pub model: PathBuf,
    /// `training_data/<name>.fit`: a fingerprint of what the saved model was fitted on (the
    /// tables, the record and the GP settings); a train that would fit the same again keeps it.
    pub fit_stamp: PathBuf,
    /// `models/<name>_figures/`: parity plots and residual histograms of the fit.
    pub figures: PathBuf,
}

impl TrainPaths {
    /// The layout under `dir` for the train called `name`.
    pub fn new(dir: &Path, name: &str) -> TrainPaths {
        let (s, t, m) = (
            dir.join("sampling"),
            dir.join("training_data"),
            dir.join("models"),
        );
        TrainPaths {
            design: s.join(format!("{name}.csv")),
            validation_design: s.join(format!("{name}_validation.csv")),
            table: t.join(format!("{name}.csv")),
            validation_table: t.join(format!("{name}_validation.csv")),
            record: t.join(format!("{name}.train.json")),
            model: m.join(format!("{name}.json")),
            fit_stamp: t.join(format!("{name}.fit")),
            figures: m.join(format!("{name}_figures")),
        }
    }
}

/// Seeds of the four random streams of a train with seed `seed`: the validation design and its
/// runs use `seed + 1`, so that they share no random numbers with the training set.
pub fn seeds(seed: u64) -> (u64, u64) {
    (seed, seed.wrapping_add(1))
}

/// Brings the design at `path` to `n` rows: creates it, extends it (its rows stay first,
/// unchanged), or keeps it. Returns (rows before, rows after). A design with more rows than `n`
/// is refused: a train never drops simulated rows silently.
pub fn ensure_design(
    path: &Path,
    space: &Space,
    sampler: &dyn Sampler,
    n: usize,
    seed: u64,
) -> Result<(usize, usize)> {
    let mut design = if path.exists() {
        Design::read(path, Some(space))?
    } else {
        Design::empty(Some(space), space.dim())
    };
    let before = design.len();
    if before > n {
        return Err(Error::input(
            path.display().to_string(),
            "rows",
            format!(
                "at most {n} rows (--n or --validation), found {before}: pass {before} or more \
                 (a train extends a design, it never drops rows)"
            ),
        ));
    }
    if before < n {
        let new = extend_design(sampler, &design.unit, n - before, seed)
            .map_err(|e| Error::invalid(format!("sampling {}: {e}", path.display())))?;
        design.append_unit(Some(space), &new);
        if let Some(dir) = path.parent() {
            std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        }
        design.write(path)?;
    }
    Ok((before, design.len()))
}

/// The training design's sampler (FSSF-f, sequential: extending it keeps its space filling) and
/// the validation design's (uniform random: an unbiased sample of the space).
pub fn samplers() -> (Box<dyn Sampler>, Box<dyn Sampler>) {
    (Box::new(fssf::Fssf::forward()), Box::new(random::Random))
}

/// The plan of one table: every design row with the campaign seed.
pub fn plan(
    experiment: &dyn Experiment,
    design: &Path,
    seed: u64,
    settings: &ExperimentSettings,
    shard: Option<Shard>,
) -> Result<Plan> {
    Plan::new(experiment, design, &[], seed, settings, shard)
}

/// Inputs of the fit: every parameter of the space that varies in the design, and the fixed ones
/// the similarity absorbs (they act through its groups); a fixed parameter nothing absorbs is a
/// constant and is left out.
pub fn fit_inputs(space: &Space, absorbed: &[String]) -> Vec<String> {
    space
        .parameters
        .iter()
        .filter(|p| !p.is_fixed() || absorbed.contains(&p.name))
        .map(|p| p.name.clone())
        .collect()
}

/// What produced a trained model, written beside its tables.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct TrainRecord {
    /// Version of mbgc that ran the train.
    pub mbgc_version: String,
    /// The space file, as given.
    pub space: String,
    /// The calibration experiment (`shear-box`, ...).
    pub experiment: String,
    /// The experiment's model class (comma-separated effects); `None` for an experiment without
    /// a contact law.
    pub model_class: Option<String>,
    /// The experiment's box scale in effect (shear box: k, the smallest side in d_max).
    pub box_scale: Option<f64>,
    /// The shear box's rest rule when it is not the kinetic one (absent in every record from
    /// before the rule could be chosen).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rest_rule: Option<String>,
    /// Rows of the training design (DEM runs to fit on).
    pub n: usize,
    /// Rows of the validation design (0: none).
    pub validation: usize,
    /// Sampler of the training design (`fssf-f`).
    pub design_method: String,
    /// Sampler of the validation design (`random`).
    pub validation_method: String,
    /// Seed of the training design and its runs.
    pub seed: u64,
    /// Seed of the validation design and its runs (`seed + 1`).
    pub validation_seed: u64,
    /// The responses fitted.
    pub responses: Vec<String>,
    /// The fit's inputs (see [`fit_inputs`]).
    pub inputs: Vec<String>,
    /// The dimensionless groups fitted in, as `name = monomial` (empty without a similarity).
    pub groups: Vec<String>,
    /// The trained model this one extends with effects (`--extends`), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub extends: Option<ExtendsRecord>,
    /// Each parameter of the space as the designs were made for it (`name: min..max scale`, or
    /// `name = value` when fixed): a later train under the same name with another space would
    /// otherwise extend the old designs as if they filled the new one. Absent in records
    /// written before it was kept.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub space_parameters: Option<Vec<String>>,
    /// The model whose equations the fit corrected (`--correct`), if not the extended one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub correct: Option<String>,
    /// Groups the equations were not allowed to read (`--unread-groups`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unread_groups: Vec<String>,
    /// Support groups that were not to bound the model (`--unbounded-groups`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub unbounded_groups: Vec<String>,
    /// Other campaigns' (training, validation) tables fitted beside this train's (`--also-fit`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub also_fit: Vec<(String, String)>,
}

impl TrainRecord {
    /// The record a train wrote (`TrainPaths::record`).
    pub fn load(path: &Path) -> Result<TrainRecord> {
        let text = crate::error::read_to_string(path)?;
        TrainRecord::from_json(&text, path)
    }

    /// A record from its JSON text; `path` names it in errors.
    pub fn from_json(text: &str, path: &Path) -> Result<TrainRecord> {
        serde_json::from_str(text)
            .map_err(|e| Error::input(path.display(), "JSON", format!("a train record ({e})")))
    }

    /// The `mbgc train` command that made the model `name` of this record with the fit
    /// settings `gp`, into `out_dir` (the default directory when `None`); `partial` when the
    /// fit ran on part of the training table.
    pub fn command(
        &self,
        name: &str,
        out_dir: Option<&Path>,
        gp: &mbgc_sr::Config,
        partial: bool,
    ) -> String {
        let mut c = format!(
            "mbgc train --space {} --experiment {} --name {name}",
            self.space, self.experiment
        );
        if let Some(e) = &self.extends {
            c += &format!(" --extends {}", e.from);
            if e.correction {
                c += " --correction";
            }
        }
        if let Some(m) = &self.correct {
            c += &format!(" --correct {m}");
        }
        if !self.unread_groups.is_empty() {
            c += &format!(" --unread-groups {}", self.unread_groups.join(","));
        }
        if !self.unbounded_groups.is_empty() {
            c += &format!(" --unbounded-groups {}", self.unbounded_groups.join(","));
        }
        for (t, v) in &self.also_fit {
            c += &format!(" --also-fit {t},{v}");
        }
        c += &format!(
            " --n {} --validation {} --seed {}",
            self.n, self.validation, self.seed
        );
        if let Some(d) = out_dir {
            c += &format!(" --out-dir {}", d.display());
        }
        c += &format!(
            " --population {} --generations {} --parsimony {} --max-length {} --restarts {} \
             --select {}",
            gp.population,
            gp.generations,
            gp.parsimony,
            gp.max_length,
            gp.restarts,
            gp.selection.flag()
        );
        if partial {
            c += " --partial";
        }
        c
    }
}

/// The parameters of a space as a train record keeps them.
pub fn space_parameters(space: &Space) -> Vec<String> {
    space
        .parameters
        .iter()
        .map(|p| match p.fixed {
            Some(v) => format!("{} = {v:?}", p.name),
            None => format!("{}: {:?}..{:?} {:?}", p.name, p.min, p.max, p.scale),
        })
        .collect()
}

/// What an extension added to which model, and where the copied runs lie.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub struct ExtendsRecord {
    /// The extended train as `--extends` named it: its name or its model file.
    pub from: String,
    /// The effects the extension added.
    pub added: Vec<String>,
    /// Each added parameter at the value where the old runs lie.
    pub off_face: Vec<(String, f64)>,
    /// Each widened parameter with its old range, inside which the old runs lie.
    #[serde(default)]
    pub widened: Vec<(String, [f64; 2])>,
    /// Whether the fit was a correction of the extended model's equations (`--correction`).
    #[serde(default)]
    pub correction: bool,
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPACE: &str = "name = \"t\"\n[parameters]\na = { min = 0.0, max = 1.0 }\n\
                         b = { min = 1.0, max = 10.0, scale = \"log\" }\n\
                         c = { min = 0.0, max = 2.0, fixed = 1.0 }\n";

    #[test]
    fn a_design_is_created_extended_and_never_cut() {
        let dir = tempfile::tempdir().unwrap();
        let space = Space::from_toml_str(SPACE, "s.toml").unwrap();
        let path = dir.path().join("sampling/d.csv");
        let (fssf, _) = samplers();
        assert_eq!(
            ensure_design(&path, &space, fssf.as_ref(), 8, 1).unwrap(),
            (0, 8)
        );
        let first = std::fs::read_to_string(&path).unwrap();
        assert_eq!(
            ensure_design(&path, &space, fssf.as_ref(), 8, 1).unwrap(),
            (8, 8)
        );
        assert_eq!(std::fs::read_to_string(&path).unwrap(), first);
        assert_eq!(
            ensure_design(&path, &space, fssf.as_ref(), 12, 1).unwrap(),
            (8, 12)
        );
        let grown = std::fs::read_to_string(&path).unwrap();
        assert!(grown.starts_with(&first), "the old rows stay first");
        assert_eq!(grown.lines().count(), 13);
        let e = ensure_design(&path, &space, fssf.as_ref(), 10, 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("d.csv") && e.contains("found 12"), "{e}");
        assert_eq!(fit_inputs(&space, &[]), vec!["a", "b"]);
        assert_eq!(fit_inputs(&space, &["c".into()]), vec!["a", "b", "c"]);
    }
}
