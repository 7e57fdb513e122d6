//! Measurement sets: several samples of one material (sieve fractions, or one material in several
//! experiments), each with its PSD, its measured responses and the experiment that measured
//! them, and which parameters are known, searched once for all samples or searched per sample.
//!
//! ```toml
//! name = "Limestone, four sieve fractions"
//! model_error_correlation = 0.8      # optional: share of a model's error common to the samples
//! [model]
//! class = "hertz,mindlin,epsd2"      # the model class the measurements are compared with
//! [fixed]                            # known for every sample
//! E_p = 5e6
//! [bounds]                           # optional: narrower ranges of searched parameters
//! mu_pp = [0.2, 0.9]
//! per_sample = []                    # searched separately for each sample (default: shared)
//! [model_error]                      # optional: the metamodel's own error per response
//! shear_angle = 1.3                  # (default: its validation RMSE)
//! [candidates.sjkr]                  # optional: settings of a candidate effect
//! fixed = { ced_pw = 0 }
//! [[sample]]
//! name = "2 mm"
//! experiment = "shear-box"
//! psd = { d50_mm = 2.0, sigma_ln = 0.12 }   # or: sieve = "fraction_2mm.csv"
//! measured.shear_angle = { value = 41.2, sd = 1.1 }
//! fixed = {}                         # optional: known values of this sample only
//! ```

use serde::Deserialize;
use std::path::Path;

use crate::error::{from_toml, read_to_string, Entries, Error, Result};
use crate::material::{
    finite, measured_values, min_max, psd_spec, Measured, MeasuredFile, PsdFile, PsdSpec,
};
use crate::model_table::{refuse_inactive_parameters, ModelTable};
use mbgc_dem::contact::{all_effects, EffectSpec, ModelClass, Pair};

/// One sample of the material: its PSD, the experiment that measured it and what it measured.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// Sample name, unique in the set (e.g. a sieve fraction, "2 mm").
    pub name: String,
    /// How errors name it: `sample["2 mm"]`.
    pub field: String,
    /// Experiment that measured it, as on the command line (e.g. `shear-box`).
    pub experiment: String,
    /// Its particle size distribution: (d50 in mm, sigma_ln) or a sieve file to fit.
    pub psd: Option<PsdSpec>,
    /// Measured responses, each a value and standard deviation in the response's unit.
    pub measured: Vec<Measured>,
    /// Parameters known for this sample only, with their values.
    pub fixed: Vec<(String, f64)>,
}

/// What the file says about one candidate effect.
#[derive(Clone, Debug)]
pub struct CandidateSettings {
    /// The candidate effect.
    pub effect: &'static EffectSpec,
    /// Parameters of the effect held at known values when it is tried.
    pub fixed: Vec<(String, f64)>,
    /// Narrower search ranges of its parameters, `[min, max]`.
    pub bounds: Vec<(String, [f64; 2])>,
}

/// Several samples of one material and what is known about its parameters: the input of
/// `mbgc diagnose`.
#[derive(Clone, Debug)]
pub struct MeasurementSet {
    /// Name of the set, from the file.
    pub name: String,
    /// Where the set came from (file path), named in errors.
    pub source: String,
    /// The model class the user compares the measurements with.
    pub class: ModelClass,
    /// Parameters known for every sample, with their values.
    pub fixed: Vec<(String, f64)>,
    /// Narrower search ranges `[min, max]` of searched parameters.
    pub bounds: Vec<(String, [f64; 2])>,
    /// Parameters searched separately for each sample rather than shared.
    pub per_sample: Vec<String>,
    /// Per response, the metamodel's own standard error in the response's unit (default: its
    /// validation RMSE).
    pub model_error: Vec<(String, f64)>,
    /// Correlation, in [0, 1), of one model's error for one response between the samples
    /// (default [`super::covariance::DEFAULT_CORRELATION`]).
    pub model_error_correlation: f64,
    /// Settings of candidate effects given in the file.
    pub candidates: Vec<CandidateSettings>,
    /// The samples, in file order.
    pub samples: Vec<Sample>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields, expecting = "a measurement-set file")]
struct SetFile {
    name: Option<String>,
    model: Option<ModelTable>,
    #[serde(default)]
    fixed: Entries<f64>,
    #[serde(default)]
    bounds: Entries<Vec<f64>>,
    #[serde(default)]
    per_sample: Vec<String>,
    #[serde(default)]
    model_error: Entries<f64>,
    model_error_correlation: Option<f64>,
    #[serde(default)]
    candidates: Entries<CandidateFile>,
    #[serde(default)]
    sample: Vec<SampleFile>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a sample: name, experiment, psd, measured and optionally fixed"
)]
struct SampleFile {
    name: Option<String>,
    experiment: Option<String>,
    psd: Option<PsdFile>,
    #[serde(default)]
    measured: Entries<MeasuredFile>,
    #[serde(default)]
    fixed: Entries<f64>,
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a table with `fixed = { ... }` and/or `bounds = { ... }`"
)]
struct CandidateFile {
    #[serde(default)]
    fixed: Entries<f64>,
    #[serde(default)]
    bounds: Entries<Vec<f64>>,
}

fn values(entries: Entries<f64>, file: &str, table: &str) -> Result<Vec<(String, f64)>> {
    entries
        .0
        .into_iter()
        .map(|(k, v)| Ok((k.clone(), finite(v, file, &format!("{table}.{k}"))?)))
        .collect()
}

fn ranges(entries: Entries<Vec<f64>>, file: &str, table: &str) -> Result<Vec<(String, [f64; 2])>> {
    let mut out = Vec::new();
    for (k, v) in entries.0 {
        let [lo, hi] = min_max(v, file, &format!("{table}.{k}"))?;
        out.push((k, [lo, hi]));
    }
    Ok(out)
}

fn refuse_twice(
    a: &[(String, f64)],
    b: &[String],
    file: &str,
    field: &str,
    why: &str,
) -> Result<()> {
    if let Some((n, _)) = a.iter().find(|(n, _)| b.contains(n)) {
        return Err(Error::input(file, format!("{field}.{n}"), why.to_string()));
    }
    Ok(())
}

impl SetFile {
    fn validate(self, file: &str) -> Result<MeasurementSet> {
        let name = self.name.unwrap_or_else(|| {
            Path::new(file)
                .file_stem()
                .map_or("measurements".into(), |s| s.to_string_lossy().to_string())
        });
        let class = self
            .model
            .ok_or_else(|| {
                Error::input(
                    file,
                    "model.class",
                    "the model class the measurements are compared with, e.g. [model] class = \
                     \"hertz,mindlin,epsd2\"",
                )
            })?
            .class(file)?;
        let fixed = values(self.fixed, file, "fixed")?;
        let bounds = ranges(self.bounds, file, "bounds")?;
        refuse_inactive_parameters(
            &class,
            fixed.iter().map(|(n, _)| n.as_str()),
            file,
            "fixed",
            "this measurement set",
        )?;
        refuse_inactive_parameters(
            &class,
            bounds.iter().map(|(n, _)| n.as_str()),
            file,
            "bounds",
            "this measurement set",
        )?;
        let fixed_names: Vec<String> = fixed.iter().map(|(n, _)| n.clone()).collect();
        if let Some((n, _)) = bounds.iter().find(|(n, _)| fixed_names.contains(n)) {
            return Err(Error::input(
                file,
                format!("bounds.{n}"),
                format!("{n} is also in [fixed]: give it a value or a range, not both"),
            ));
        }
        for (k, n) in self.per_sample.iter().enumerate() {
            let field = format!("per_sample[{k}]");
            if !crate::space::is_identifier(n) {
                return Err(Error::input(
                    file,
                    &field,
                    format!("a parameter name, got \"{n}\""),
                ));
            }
            if fixed_names.contains(n) {
                return Err(Error::input(
                    file,
                    &field,
                    format!("{n} is in [fixed]: a known value is not searched per sample"),
                ));
            }
            if self.per_sample[..k].contains(n) {
                return Err(Error::input(file, &field, format!("{n} listed once")));
            }
            refuse_inactive_parameters(
                &class,
                [n.as_str()],
                file,
                "per_sample",
                "this measurement set",
            )?;
        }
        let mut model_error = Vec::new();
        for (r, v) in self.model_error.0 {
            let field = format!("model_error.{r}");
            let v = finite(v, file, &field)?;
            if v < 0.0 {
                return Err(Error::input(
                    file,
                    &field,
                    format!("an error >= 0 in the response's unit, got {v}"),
                ));
            }
            model_error.push((r, v));
        }
        let model_error_correlation = match self.model_error_correlation {
            None => super::covariance::DEFAULT_CORRELATION,
            Some(v) => {
                let v = finite(v, file, "model_error_correlation")?;
                if !(0.0..1.0).contains(&v) {
                    return Err(Error::input(
                        file,
                        "model_error_correlation",
                        format!(
                            "a correlation in [0, 1) of the model's error between samples, got {v}"
                        ),
                    ));
                }
                v
            }
        };
        let mut candidates = Vec::new();
        for (effect, c) in self.candidates.0 {
            let field = format!("candidates.{effect}");
            let spec = all_effects()
                .into_iter()
                .find(|e| e.name == effect && !e.params.is_empty())
                .ok_or_else(|| {
                    let known: Vec<&str> = all_effects()
                        .iter()
                        .filter(|e| {
                            e.params.iter().all(|p| p.off.is_some()) && !e.params.is_empty()
                        })
                        .map(|e| e.name)
                        .collect();
                    Error::input(
                        file,
                        &field,
                        format!(
                            "an effect that can be switched on (one of: {})",
                            known.join(", ")
                        ),
                    )
                })?;
            if class.effects().iter().any(|e| e.name == spec.name) {
                return Err(Error::input(
                    file,
                    &field,
                    format!("an effect the class {class} lacks; it has {effect} already"),
                ));
            }
            let cfixed = values(c.fixed, file, &format!("{field}.fixed"))?;
            let cbounds = ranges(c.bounds, file, &format!("{field}.bounds"))?;
            let named = cfixed
                .iter()
                .map(|(n, _)| ("fixed", n))
                .chain(cbounds.iter().map(|(n, _)| ("bounds", n)));
            for (table, n) in named {
                if !spec.params.iter().any(|p| p.names.contains(&n.as_str())) {
                    let own: Vec<&str> = spec.params.iter().flat_map(|p| p.names).collect();
                    return Err(Error::input(
                        file,
                        format!("{field}.{table}.{n}"),
                        format!(
                            "not a parameter of {effect}; expected one of: {}",
                            own.join(", ")
                        ),
                    ));
                }
            }
            let cnames: Vec<String> = cfixed.iter().map(|(n, _)| n.clone()).collect();
            refuse_twice_ranges(&cbounds, &cnames, file, &format!("{field}.bounds"))?;
            candidates.push(CandidateSettings {
                effect: spec,
                fixed: cfixed,
                bounds: cbounds,
            });
        }
        if self.sample.is_empty() {
            return Err(Error::input(
                file,
                "sample",
                "at least one [[sample]] with its experiment, psd and measured responses",
            ));
        }
        let mut samples: Vec<Sample> = Vec::new();
        for (i, s) in self.sample.into_iter().enumerate() {
            let name = s.name.unwrap_or_else(|| format!("sample {}", i + 1));
            let prefix = format!("sample[\"{name}\"]");
            if samples.iter().any(|t| t.name == name) {
                return Err(Error::input(
                    file,
                    format!("sample[{}].name", i + 1),
                    format!("a name no other sample has (\"{name}\" is taken)"),
                ));
            }
            let experiment = s.experiment.ok_or_else(|| {
                Error::input(
                    file,
                    format!("{prefix}.experiment"),
                    format!(
                        "the experiment that measured it (one of: {})",
                        crate::campaign::experiment_names().join(", ")
                    ),
                )
            })?;
            let psd = psd_spec(s.psd, file, &format!("{prefix}."))?;
            let measured = measured_values(s.measured, file, &format!("{prefix}."))?;
            let sfixed = values(s.fixed, file, &format!("{prefix}.fixed"))?;
            refuse_inactive_parameters(
                &class,
                sfixed.iter().map(|(n, _)| n.as_str()),
                file,
                &format!("{prefix}.fixed"),
                "this measurement set",
            )?;
            refuse_twice(
                &sfixed,
                &fixed_names,
                file,
                &format!("{prefix}.fixed"),
                "also in the set's [fixed]: give it in one place",
            )?;
            refuse_twice(
                &sfixed,
                &self.per_sample,
                file,
                &format!("{prefix}.fixed"),
                "also in per_sample: a known value is not searched",
            )?;
            if psd.is_some() {
                if let Some((n, _)) = sfixed
                    .iter()
                    .chain(&fixed)
                    .find(|(n, _)| n == "d50" || n == "sigma_ln")
                {
                    return Err(Error::input(
                        file,
                        format!("{prefix}.psd"),
                        format!("{n} from psd or fixed, not both"),
                    ));
                }
            }
            samples.push(Sample {
                field: prefix,
                name,
                experiment,
                psd,
                measured,
                fixed: sfixed,
            });
        }
        Ok(MeasurementSet {
            name,
            source: file.to_string(),
            class,
            fixed,
            bounds,
            per_sample: self.per_sample,
            model_error,
            model_error_correlation,
            candidates,
            samples,
        })
    }
}

fn refuse_twice_ranges(
    b: &[(String, [f64; 2])],
    fixed: &[String],
    file: &str,
    field: &str,
) -> Result<()> {
    if let Some((n, _)) = b.iter().find(|(n, _)| fixed.contains(n)) {
        return Err(Error::input(
            file,
            format!("{field}.{n}"),
            format!("{n} is also fixed: give it a value or a range, not both"),
        ));
    }
    Ok(())
}

impl MeasurementSet {
    /// Reads and checks a measurement-set TOML file; relative sieve paths are resolved against the
    /// file's directory.
    pub fn from_file(path: &Path) -> Result<MeasurementSet> {
        let text = read_to_string(path)?;
        let mut m = MeasurementSet::from_toml_str(&text, &path.display().to_string())?;
        let dir = path.parent().unwrap_or(Path::new("."));
        for s in &mut m.samples {
            if let Some(PsdSpec::Sieve(p)) = &mut s.psd {
                if p.is_relative() {
                    *p = dir.join(&*p);
                }
            }
        }
        Ok(m)
    }

    /// Parses a measurement set from TOML text; `source` names it in errors. Relative sieve paths
    /// are left as written.
    pub fn from_toml_str(text: &str, source: &str) -> Result<MeasurementSet> {
        from_toml::<SetFile>(text, source)?.validate(source)
    }

    /// Settings of a candidate effect (empty when the file says nothing about it).
    pub fn candidate(&self, effect: &'static EffectSpec) -> CandidateSettings {
        self.candidates
            .iter()
            .find(|c| c.effect.name == effect.name)
            .cloned()
            .unwrap_or(CandidateSettings {
                effect,
                fixed: Vec::new(),
                bounds: Vec::new(),
            })
    }

    /// Number of measured values over all samples.
    pub fn measurements(&self) -> usize {
        self.samples.iter().map(|s| s.measured.len()).sum()
    }
}

/// The effects a class lacks that could be switched on in an empty slot and off again by a value
/// (the candidates of a diagnosis).
pub fn switchable_effects(class: &ModelClass) -> Vec<&'static EffectSpec> {
    let empty: Vec<mbgc_dem::contact::Slot> = mbgc_dem::contact::Slot::ALL
        .into_iter()
        .filter(|s| !class.effects().iter().any(|e| e.slot == *s))
        .collect();
    all_effects()
        .into_iter()
        .filter(|e| {
            empty.contains(&e.slot)
                && !e.params.is_empty()
                && e.params.iter().all(|p| p.off.is_some())
        })
        .collect()
}

/// Whether `name` is one of the effect's parameters for a kind of contact.
pub fn owns(effect: &EffectSpec, name: &str) -> bool {
    effect
        .params
        .iter()
        .any(|p| Pair::BOTH.iter().any(|&pair| p.name(pair) == name))
}
