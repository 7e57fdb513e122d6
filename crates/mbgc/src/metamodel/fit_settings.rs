//! What a fit is asked to do, checked before any generation runs: which columns are inputs and
//! responses, how many rows are held out, how inputs are scaled, the GP settings.

use super::training_table::TrainingTable;
use crate::error::{Error, Result};
use crate::similarity::Similarity;
use crate::space::Space;
use mbgc_dem::contact::ModelClass;
use mbgc_sr as gp;

/// The settings of [`super::fit`]: built with [`FitSettings::new`] and the setters, validated by
/// [`FitSettings::check`] (which `fit` calls first).
#[derive(Clone, Debug)]
pub struct FitSettings {
    /// Input columns, in the order the model's equations number their variables.
    pub inputs: Vec<String>,
    /// Response columns; one equation is fitted to each.
    pub targets: Vec<String>,
    /// Share of rows held out as a test set (seeded shuffle), in [0, 0.9].
    pub test_fraction: f64,
    /// Scale inputs to the unit interval as the space says (linear or log), record the
    /// parameters it fixes as the model's constants, and take its `[model] class`.
    pub space: Option<Space>,
    /// The genetic-programming settings (population, generations, functions, seed, ...).
    pub config: gp::Config,
    /// The model class of the rows when the table does not say; a table's `model_class` column
    /// and the space's class must agree with it.
    pub model_class: Option<ModelClass>,
    /// Fit in the experiment's dimensionless groups (inputs they absorb are not offered to GP;
    /// scaled responses are fitted divided by their factor); the equations are composed back
    /// into the physical inputs.
    pub similarity: Option<Similarity>,
    /// Rows never trained on, scored as each response's `validation` metrics.
    pub validation: Option<TrainingTable>,
    /// The model this fit extends (`train --extends`): for each response it also predicts, GP
    /// fits only what the data add to it, and the saved equation is its equation plus the
    /// fitted correction. Its inputs must be among `inputs`.
    pub extends: Option<Box<super::model::Metamodel>>,
}

impl FitSettings {
    /// Fit `targets` on `inputs` with the default GP settings, 10 % of the rows held out and no
    /// scaling.
    pub fn new(inputs: Vec<String>, targets: Vec<String>) -> FitSettings {
        FitSettings {
            inputs,
            targets,
            test_fraction: 0.1,
            space: None,
            config: gp::Config::default(),
            model_class: None,
            similarity: None,
            validation: None,
            extends: None,
        }
    }

    /// Holds out this share of the rows as a test set.
    pub fn test_fraction(mut self, share: f64) -> Self {
        self.test_fraction = share;
        self
    }

    /// Scales the inputs as `space` says and takes its constants and model class.
    pub fn space(mut self, space: Space) -> Self {
        self.space = Some(space);
        self
    }

    /// The genetic-programming settings.
    pub fn config(mut self, config: gp::Config) -> Self {
        self.config = config;
        self
    }

    /// The model class of the rows (when the table does not record it).
    pub fn model_class(mut self, class: ModelClass) -> Self {
        self.model_class = Some(class);
        self
    }

    /// Fits in the experiment's dimensionless groups.
    pub fn similarity(mut self, similarity: Similarity) -> Self {
        self.similarity = Some(similarity);
        self
    }

    /// Scores every response on these rows too.
    pub fn validation(mut self, table: TrainingTable) -> Self {
        self.validation = Some(table);
        self
    }

    /// Refuses settings a fit cannot honour: no inputs or responses, a column named twice or as
    /// both, a test share outside [0, 0.9], bad GP settings, a group made of a non-input.
    pub fn check(&self) -> Result<()> {
        if self.inputs.is_empty() {
            return Err(Error::invalid(
                "--inputs: expected at least one input column",
            ));
        }
        if self.targets.is_empty() {
            return Err(Error::invalid(
                "--targets: expected at least one target column",
            ));
        }
        for (option, list) in [("--inputs", &self.inputs), ("--targets", &self.targets)] {
            if let Some((k, name)) = list
                .iter()
                .enumerate()
                .find(|(k, n)| list[..*k].contains(n))
            {
                return Err(Error::invalid(format!(
                    "{option}: {name} is given twice (position {}); expected each column once",
                    k + 1
                )));
            }
        }
        for t in &self.targets {
            if self.inputs.contains(t) {
                return Err(Error::invalid(format!(
                    "--targets: {t} is also an input; a response cannot explain itself"
                )));
            }
        }
        if !(0.0..=0.9).contains(&self.test_fraction) {
            return Err(Error::invalid(format!(
                "--test-fraction: expected a value in [0, 0.9], got {}",
                self.test_fraction
            )));
        }
        self.config
            .check()
            .map_err(|e| Error::invalid(format!("GP settings: {e}")))?;
        let needed = self
            .similarity
            .as_ref()
            .map(Similarity::needed_inputs)
            .unwrap_or_default();
        for a in &needed {
            if !self.inputs.contains(a) {
                return Err(Error::invalid(format!(
                    "--inputs: the experiment's groups and scaled responses are made of {}, so \
                     {a} must be an input",
                    needed.join(", ")
                )));
            }
        }
        Ok(())
    }

    /// The inputs the similarity's groups absorb (empty without a similarity).
    pub(crate) fn absorbed(&self) -> Vec<String> {
        self.similarity
            .as_ref()
            .map(Similarity::absorbed)
            .unwrap_or_default()
    }
}
