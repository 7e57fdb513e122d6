//! `mbgc validate`: rerun the DEM experiment at calibrated parameters and compare with the
//! measurements (and with what the metamodel predicted there).

use mbgc_output::say;
use mbgc_output::Output;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use mbgc::campaign::registry::{experiment_by_name, ExperimentSettings};
use mbgc::dem::contact::ModelClass;
use mbgc::error::{read_to_string, Error};
use mbgc::experiments::{ParamSet, RunOptions};
use mbgc::material::{Material, PsdSpec};
use mbgc::outputs::refuse_overwriting_inputs;

#[derive(Debug, Args)]
pub struct ValidateArgs {
    #[arg(long)]
    pub material: PathBuf,
    /// Parameter file written by `mbgc calibrate --out` (`[parameters]`, optional `[predicted]`).
    #[arg(long)]
    pub params: PathBuf,
    #[arg(long, default_value = "shear-box", help = crate::simulate::experiment_help())]
    pub experiment: String,
    /// Box scale of the experiment (use the campaign's).
    #[arg(long)]
    pub box_scale: Option<f64>,
    /// Effects of the contact law, comma-separated [default: the `[model] class` of --params or
    /// --material, else hertz,mindlin,epsd2].
    #[arg(long, value_name = "EFFECTS", value_parser = crate::simulate::parse_model_class)]
    pub model_class: Option<ModelClass>,
    /// Parameters the experiment needs that the model did not have, e.g. `--set nu_p=0.3`.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    pub set: Vec<String>,
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
    /// Side view of the final state (SVG or PNG).
    #[arg(long)]
    pub picture: Option<PathBuf>,
    /// Largest accepted relative deviation |DEM - measured| / |measured| (e.g. 0.05); with it the
    /// command exits 1 when a response is further off. Without it deviations are only reported.
    #[arg(long)]
    pub tolerance: Option<f64>,
    /// Standard output holds one JSON object (the comparison); text goes to standard error.
    #[arg(long)]
    pub json: bool,
}

/// The picture can be written: a known extension and a directory that takes a file. Checked
/// before the DEM runs, so a bad path never costs the run's result.
fn check_picture(p: &std::path::Path) -> anyhow::Result<()> {
    let ext = p
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("svg" | "png")) {
        anyhow::bail!(
            "--picture {}: expected a file ending in .svg or .png",
            p.display()
        );
    }
    let dir = match p.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => std::path::Path::new("."),
    };
    std::fs::create_dir_all(dir)
        .and_then(|()| tempfile::tempfile_in(dir))
        .map(drop)
        .map_err(|e| {
            anyhow::anyhow!(
                "--picture {}: cannot write in {} ({e}); expected a writable directory",
                p.display(),
                dir.display()
            )
        })
}

/// The parameters, the predicted responses and the `[model] class` of a parameter file.
pub(crate) type ParamsFile = (
    ParamSet,
    Vec<(String, f64)>,
    Option<ModelClass>,
    Option<Trained>,
);

/// The experiment and box scale a parameter file's metamodel was trained on (its `[experiment]`
/// table, written by `calibrate --out`).
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Trained {
    name: String,
    box_scale: Option<f64>,
    /// The shear box's rest rule of the training runs (absent: kinetic).
    #[serde(default)]
    rest_rule: Option<String>,
}

pub(crate) fn read_params(path: &std::path::Path) -> anyhow::Result<ParamsFile> {
    let file = path.display().to_string();
    let doc: toml::Table = read_to_string(path)?
        .parse()
        .map_err(|e: toml::de::Error| {
            Error::input(&file, "TOML syntax", e.message().to_string())
        })?;
    let table = |key: &str| -> anyhow::Result<Vec<(String, f64)>> {
        let Some(t) = doc.get(key) else {
            return Ok(Vec::new());
        };
        let t = t
            .as_table()
            .ok_or_else(|| Error::input(&file, key, "a table of name = number"))?;
        t.iter()
            .map(|(k, v)| {
                let x = v
                    .as_float()
                    .or_else(|| v.as_integer().map(|i| i as f64))
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| Error::input(&file, format!("{key}.{k}"), "a finite number"))?;
                Ok((k.clone(), x))
            })
            .collect()
    };
    let params = table("parameters")?;
    if params.is_empty() {
        anyhow::bail!(Error::input(&file, "parameters", "a [parameters] table"));
    }
    for key in doc.keys() {
        if !["parameters", "predicted", "model", "experiment", "material"].contains(&key.as_str()) {
            anyhow::bail!(Error::input(
                &file,
                key,
                "unknown; expected [parameters], [predicted], [model], [experiment] or material"
            ));
        }
    }
    let class = match doc.get("model") {
        None => None,
        Some(m) => {
            let t: mbgc::model_table::ModelTable = m
                .clone()
                .try_into()
                .map_err(|e: toml::de::Error| Error::input(&file, "model", e.message()))?;
            Some(t.class(&file)?)
        }
    };
    let trained = match doc.get("experiment") {
        None => None,
        Some(e) => Some(
            e.clone()
                .try_into::<Trained>()
                .map_err(|e| Error::input(&file, "experiment", e.message()))?,
        ),
    };
    Ok((
        ParamSet::from_pairs(&params),
        table("predicted")?,
        class,
        trained,
    ))
}

/// The class a validation runs: `--model-class`, the parameter file's, the material's, in that
/// order; two that disagree are refused, since the run would not be what one of them says.
fn resolve_class(
    flag: Option<ModelClass>,
    params: (Option<ModelClass>, &std::path::Path),
    material: (Option<ModelClass>, &std::path::Path),
) -> anyhow::Result<Option<ModelClass>> {
    let given: Vec<(ModelClass, String)> = [
        flag.map(|c| (c, "--model-class".to_string())),
        params
            .0
            .map(|c| (c, format!("{} ([model] class)", params.1.display()))),
        material
            .0
            .map(|c| (c, format!("{} ([model] class)", material.1.display()))),
    ]
    .into_iter()
    .flatten()
    .collect();
    if let Some((c0, w0)) = given.first() {
        if let Some((c, w)) = given.iter().find(|(c, _)| c != c0) {
            anyhow::bail!(
                "model class: {w0} says {c0} but {w} says {c}; expected one class (the one the \
                 parameters were calibrated with)"
            );
        }
    }
    Ok(given.first().map(|g| g.0))
}

pub fn run(a: &ValidateArgs) -> anyhow::Result<()> {
    let report = Output::new(a.json);
    if a.threads == 0 {
        anyhow::bail!("--threads 0: expected at least 1");
    }
    if let Some(t) = a.tolerance {
        if !(t.is_finite() && t > 0.0) {
            anyhow::bail!("--tolerance {t}: expected a positive relative deviation such as 0.05");
        }
    }
    let material = Material::from_file(&a.material)?;
    if let Some(p) = &a.picture {
        check_picture(p)?;
        let sieve = format!("the sieve analysis of {}", a.material.display());
        let mut inputs: Vec<(&str, &std::path::Path)> =
            vec![("--material", &a.material), ("--params", &a.params)];
        if let Some(PsdSpec::Sieve(s)) = &material.psd {
            inputs.push((&sieve, s));
        }
        refuse_overwriting_inputs("--picture", p, &inputs)?;
    }
    let (mut params, predicted, params_class, trained) = read_params(&a.params)?;
    // The DEM must run the experiment, at the scale, the metamodel was trained on.
    let mut box_scale = a.box_scale;
    if let Some(t) = &trained {
        if t.name != a.experiment {
            anyhow::bail!(
                "--experiment {}: the model behind {} was trained on {} runs; validating in \
                 another experiment compares nothing it predicts",
                a.experiment,
                a.params.display(),
                t.name
            );
        }
        match (a.box_scale, t.box_scale) {
            (Some(k), Some(trained)) if (k - trained).abs() > 1e-9 * trained => anyhow::bail!(
                "--box-scale {k}: the model behind {} was trained at box scale {trained}; the \
                 responses depend on the scale (a smaller box reads a steeper angle), so a run at \
                 {k} does not test it; drop --box-scale or pass {trained}",
                a.params.display()
            ),
            (None, Some(trained)) => box_scale = Some(trained),
            _ => {}
        }
    }
    let class = resolve_class(
        a.model_class,
        (params_class, &a.params),
        (material.model_class, &a.material),
    )?;
    if let Some((d50, sigma)) = material.psd_parameters()? {
        if params.get("d50").is_none() {
            params.set("d50", d50);
        }
        if params.get("sigma_ln").is_none() {
            params.set("sigma_ln", sigma);
        }
    }
    let exp = experiment_by_name(
        &a.experiment,
        &ExperimentSettings {
            box_scale,
            model_class: class,
            // The DEM reruns the procedure the metamodel's runs had.
            rest_rule: trained
                .as_ref()
                .and_then(|t| t.rest_rule.as_deref())
                .map(mbgc::experiments::shear_box::RestRule::parse)
                .transpose()
                .map_err(|e| {
                    anyhow::anyhow!("{}: [experiment] rest_rule: {e}", a.params.display())
                })?,
            ..Default::default()
        },
    )?;
    // The class the experiment was built with (the default when no source named one).
    let class = exp.class().copied().unwrap_or_default();
    for (name, _) in params.iter() {
        class
            .refuse_inactive(name, exp.pairs(), exp.name())
            .map_err(|e| {
                Error::input(
                    a.params.display(),
                    format!("parameters.{name}"),
                    e.to_string(),
                )
            })?;
    }
    let known: Vec<&str> = exp
        .parameters()
        .into_iter()
        .chain(exp.optional_parameters())
        .collect();
    // A name the experiment does not read would be carried along and do nothing.
    for (name, _) in params.iter() {
        if !known.contains(&name) {
            anyhow::bail!(Error::input(
                a.params.display(),
                format!("parameters.{name}"),
                format!(
                    "not a parameter of {}; expected one of: {}",
                    exp.name(),
                    known.join(", ")
                )
            ));
        }
    }
    // The material's fixed values are measurements or choices the calibration kept; a parameter
    // file that says otherwise would validate another material.
    for (name, fixed) in &material.fixed {
        if let Some(v) = params.get(name) {
            if (v - fixed).abs() > 1e-12 * fixed.abs().max(1e-300) {
                anyhow::bail!(Error::input(
                    a.params.display(),
                    format!("parameters.{name}"),
                    format!(
                        "{fixed}, the value {} fixes, found {v}; calibrate again or remove it \
                         from one of the files",
                        a.material.display()
                    )
                ));
            }
        }
    }
    for s in &a.set {
        let (k, v) = mbgc::campaign::parse_set(s)?;
        class
            .refuse_inactive(&k, exp.pairs(), exp.name())
            .map_err(|e| anyhow::anyhow!("--set {s}: {e}"))?;
        if !known.contains(&k.as_str()) {
            anyhow::bail!(
                "--set {s}: {} has no parameter {k}; expected one of {}",
                exp.name(),
                known.join(", ")
            );
        }
        if let Some(old) = params.get(&k) {
            anyhow::bail!(
                "--set {s}: {k} is already {old} in {} (calibrated, or from the material's PSD); \
                 expected --set only for parameters the model did not have",
                a.params.display()
            );
        }
        params.set(&k, v);
    }
    let responses = exp.responses();
    if !material
        .measured
        .iter()
        .any(|m| responses.contains(&m.response.as_str()))
    {
        anyhow::bail!(
            "{}: none of the measured responses ({}) is measured by the {} experiment (it gives \
             {}): validation would compare nothing; expected another --experiment",
            a.material.display(),
            material
                .measured
                .iter()
                .map(|m| m.response.as_str())
                .collect::<Vec<_>>()
                .join(", "),
            exp.name(),
            responses.join(", ")
        );
    }
    exp.check(&params)
        .with_context(|| format!("{} at the parameters of {}", exp.name(), a.params.display()))?;
    let t = std::time::Instant::now();
    let out = exp.run(
        &params,
        a.seed,
        &RunOptions {
            picture: a.picture.clone(),
            threads: a.threads,
            ..RunOptions::default()
        },
    )?;
    say!(
        report,
        "{} at {} ({:.1} s):",
        exp.name(),
        a.params.display(),
        t.elapsed().as_secs_f64()
    );
    say!(
        report,
        "  {:>14} {:>12} {:>8} {:>12} {:>9} {:>8} {:>12}",
        "response",
        "measured",
        "sd",
        "DEM",
        "off %",
        "off sd",
        "metamodel"
    );
    let mut worst: Option<(String, f64)> = None;
    let mut rows = Vec::new();
    for m in &material.measured {
        let Some(dem) = out.get(&m.response) else {
            say!(
                report,
                "  {:>14} {:>12} (the {} experiment does not measure it)",
                m.response,
                m.value,
                exp.name()
            );
            continue;
        };
        let model = predicted
            .iter()
            .find(|(k, _)| *k == m.response)
            .map_or("-".to_string(), |(_, v)| format!("{v:.4}"));
        say!(
            report,
            "  {:>14} {:>12.4} {:>8.3} {:>12.4} {:>+9.2} {:>+8.2} {:>12}",
            m.response,
            m.value,
            m.sd,
            dem,
            100.0 * (dem - m.value) / m.value,
            (dem - m.value) / m.sd,
            model
        );
        rows.push(serde_json::json!({
            "response": m.response,
            "measured": m.value,
            "sd": m.sd,
            "dem": dem,
            "off_relative": (dem - m.value) / m.value,
            "off_sd": (dem - m.value) / m.sd,
            "metamodel": predicted.iter().find(|(k, _)| *k == m.response).map(|(_, v)| *v),
        }));
        let off = ((dem - m.value) / m.value).abs();
        if worst.as_ref().is_none_or(|(_, w)| off > *w || off.is_nan()) {
            worst = Some((m.response.clone(), off));
        }
    }
    let pass = worst
        .as_ref()
        .is_none_or(|(_, off)| a.tolerance.is_none_or(|t| *off <= t));
    report.object(&serde_json::json!({
        "experiment": exp.name(),
        "params": a.params,
        "seed": a.seed,
        "responses": rows,
        "tolerance": a.tolerance,
        "pass": pass,
    }))?;
    if let Some((name, off)) = worst {
        match a.tolerance {
            Some(t) if off.is_nan() || off > t => anyhow::bail!(
                "{name} is {:.2} % off the measurement, beyond --tolerance {t} ({:.2} %)",
                100.0 * off,
                100.0 * t
            ),
            Some(t) => say!(
                report,
                "largest deviation {:.2} % ({name}), within --tolerance {t}",
                100.0 * off
            ),
            None => say!(
                report,
                "largest deviation {:.2} % ({name}); give --tolerance to make it a pass/fail check",
                100.0 * off
            ),
        }
    }
    Ok(())
}
