//! `mbgc bench diagnose`: `docs/diagnose.md`, the diagnosis of fifteen synthetic measurement sets
//! made with mbgc's own DEM (a hidden cohesion, a hidden rolling resistance, a control with no
//! hidden effect, a weaker cohesion, and that with the rolling friction unknown; then issue 35's
//! control and three cohesions with both frictions unknown, on the shipped global models alone),
//! each from the measurement file to the error ladder across model versions, with figures and a
//! check of the recovered strength and the searched frictions against the truth the data were
//! made with.

use std::path::PathBuf;

use mbgc::diagnose::report::{figures, markdown};
use mbgc::diagnose::{diagnose, MeasurementSet, Options, Surrogate};
use mbgc::error::write_atomic;

#[derive(Debug)]
#[cfg_attr(feature = "cli", derive(clap::Args))]
pub struct Args {
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 1))]
    pub seed: u64,
    #[cfg_attr(feature = "cli", arg(long, default_value_t = 4000))]
    pub samples: usize,
    #[cfg_attr(feature = "cli", arg(long, default_value = "docs/diagnose.md"))]
    pub report: PathBuf,
    /// Directory of the figures (one subdirectory per case).
    #[cfg_attr(feature = "cli", arg(long, default_value = "docs/figures/diagnose"))]
    pub figures: PathBuf,
    /// Standard output holds one JSON object (where the report went); text goes to standard
    /// error.
    #[cfg_attr(feature = "cli", arg(long))]
    pub json: bool,
}

struct Case {
    file: &'static str,
    title: &'static str,
    /// The hidden effect, its parameter and the value the DEM runs used.
    truth: Option<(&'static str, &'static str, f64)>,
    /// The base model first, then the models of the classes with a candidate effect.
    models: &'static [&'static str],
}

/// The frictions every set's material was made with (searched where the set does not fix them).
const FRICTIONS: [(&str, f64); 2] = [("mu_pp", 0.5), ("mu_r_pp", 0.3)];

/// The local models of the cohesion walk-through: version 1 (no cohesion) and version 2, made
/// from it by `mbgc train --extends diagnose_local` (the guide's diagnosis chapter, docs/guide/src/diagnosis.md).
const LOCAL: &[&str] = &[
    "models/diagnose_local.json",
    "models/diagnose_local_sjkr.json",
];
const GLOBAL: &[&str] = &[
    "models/shear_box.json",
    "models/shear_box_cohesion_local.json",
];

/// The shipped global models: the base class and its cohesive extension (`mbgc diagnose`'s
/// default).
const SHIPPED: &[&str] = &["models/shear_box.json", "models/shear_box_sjkr.json"];

const CASES: [Case; 15] = [
    Case {
        file: "examples/measurements/hidden_cohesion_strong.toml",
        title: "Hidden cohesion in four sieve fractions",
        truth: Some(("sjkr", "ced_pp", 2.5e4)),
        models: LOCAL,
    },
    Case {
        file: "examples/measurements/hidden_rolling.toml",
        title: "Hidden rolling resistance",
        truth: Some(("epsd2", "mu_r_pp", 0.3)),
        models: GLOBAL,
    },
    Case {
        file: "examples/measurements/control.toml",
        title: "Control: no hidden effect",
        truth: None,
        models: LOCAL,
    },
    Case {
        file: "examples/measurements/hidden_cohesion.toml",
        title: "A weaker hidden cohesion",
        truth: Some(("sjkr", "ced_pp", 1.5e4)),
        models: LOCAL,
    },
    Case {
        file: "examples/measurements/hidden_cohesion_rolling_unknown.toml",
        title: "The weaker cohesion with the rolling friction unknown",
        truth: Some(("sjkr", "ced_pp", 1.5e4)),
        models: GLOBAL,
    },
    Case {
        file: "examples/measurements/issue35_control.toml",
        title: "Shipped models, both frictions unknown: control",
        truth: None,
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue35_ced1e4.toml",
        title: "Shipped models, both frictions unknown: cohesion 1e4 J/m3",
        truth: Some(("sjkr", "ced_pp", 1e4)),
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue35_ced2.5e4.toml",
        title: "Shipped models, both frictions unknown: cohesion 2.5e4 J/m3",
        truth: Some(("sjkr", "ced_pp", 2.5e4)),
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue35_ced4e4.toml",
        title: "Shipped models, both frictions unknown: cohesion 4e4 J/m3",
        truth: Some(("sjkr", "ced_pp", 4e4)),
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue40_fine_c.toml",
        title: "Fine, beyond the training runs: E 5 MPa, rho_p 1000, no cohesion",
        truth: None,
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue40_fine_a.toml",
        title: "Fine, beyond the training runs: E 20 MPa, rho_p 2600, no cohesion",
        truth: None,
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue40_fine_b.toml",
        title: "Fine, beyond the training runs: E 50 MPa, rho_p 1500, no cohesion",
        truth: None,
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue40_fine_c_sjkr.toml",
        title: "Fine, beyond the training runs: E 5 MPa, rho_p 1000, cohesion 1e4 J/m3",
        truth: Some(("sjkr", "ced_pp", 1e4)),
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue40_fine_a_sjkr.toml",
        title: "Fine, beyond the training runs: E 20 MPa, rho_p 2600, cohesion 2.5e4 J/m3",
        truth: Some(("sjkr", "ced_pp", 2.5e4)),
        models: SHIPPED,
    },
    Case {
        file: "examples/measurements/issue40_fine_c_sjkr_strong.toml",
        title: "Fine, beyond the training runs: E 5 MPa, rho_p 1000, cohesion 1.4e4 J/m3",
        truth: Some(("sjkr", "ced_pp", 1.4e4)),
        models: SHIPPED,
    },
];

pub fn run(a: &Args) -> anyhow::Result<()> {
    let opts = Options {
        samples: a.samples,
        seed: a.seed,
        ..Options::default()
    };
    let mut summary = String::from(
        "| case | class | chi^2/dof | p | structure | best candidate | chi^2/dof with it | fall | ln Bayes factor | truth | 90 % interval | searched frictions (truth: 90 % interval) | verdict |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut body = String::new();
    let base_dir = a.report.parent().unwrap_or(std::path::Path::new("."));
    for (k, c) in CASES.iter().enumerate() {
        let set = MeasurementSet::from_file(std::path::Path::new(c.file))?;
        let models = c
            .models
            .iter()
            .map(|p| Surrogate::from_metamodel(std::path::Path::new(p)))
            .collect::<mbgc::error::Result<Vec<_>>>()?;
        let d = diagnose(&set, &models, &opts)?;
        eprintln!("{}: {}", c.title, d.verdict);
        let dir = a.figures.join(format!("case{}", k + 1));
        let figs = figures(&d, &dir)?;
        let best = d.ranking.first();
        let (truth, interval) = match (c.truth, best) {
            (Some((effect, name, v)), _) => {
                let p = d
                    .ranking
                    .iter()
                    .find(|r| r.effect == effect)
                    .and_then(|r| r.strength.iter().find(|p| p.name == name));
                (
                    format!("{effect}: {name} = {v}"),
                    p.map_or("not evaluated".into(), |p| {
                        format!(
                            "[{:.4}, {:.4}] (x{:.2}): {}",
                            p.q05,
                            p.q95,
                            p.q95 / p.q05,
                            if p.q05 <= v && v <= p.q95 {
                                "contains it"
                            } else {
                                "misses it"
                            }
                        )
                    }),
                )
            }
            (None, _) => ("none".into(), "-".into()),
        };
        // The searched frictions in the fit of the class the data were made with: with the
        // hidden effect, or the set's own for a control.
        let made_with = match c.truth {
            Some((effect, _, _)) => d
                .extended
                .iter()
                .find(|f| f.effect.as_deref() == Some(effect)),
            None => Some(&d.base),
        };
        let frictions = made_with.map_or("not evaluated".to_string(), |f| {
            let t: Vec<String> = FRICTIONS
                .iter()
                .filter_map(|(n, v)| {
                    f.parameters.iter().find(|p| p.name == *n).map(|p| {
                        format!(
                            "{n} {v}: [{:.3}, {:.3}] {}",
                            p.q05,
                            p.q95,
                            if p.q05 <= *v && *v <= p.q95 {
                                "contains it"
                            } else {
                                "misses it"
                            }
                        )
                    })
                })
                .collect();
            if t.is_empty() {
                "none searched".into()
            } else {
                t.join("; ")
            }
        });
        summary += &format!(
            "| {} | {} | {:.2} | {:.2e} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            c.title,
            d.class,
            d.chi2_dof,
            d.p_value,
            if d.base.structured.is_empty() {
                "none".to_string()
            } else {
                d.base
                    .structured
                    .iter()
                    .map(|t| {
                        format!(
                            "{} {}{}",
                            t.kind,
                            t.of,
                            t.against
                                .as_deref()
                                .map_or(String::new(), |a| format!(" vs {a}"))
                        )
                    })
                    .collect::<Vec<_>>()
                    .join("; ")
            },
            best.map_or("-".into(), |b| b.effect.clone()),
            best.map_or("-".into(), |b| format!("{:.2}", b.chi2_dof_after)),
            best.map_or("-".into(), |b| format!("{:.1}x", b.chi2_ratio)),
            best.map_or("-".into(), |b| format!("{:.1}", b.log_bayes_factor)),
            truth,
            interval,
            frictions,
            d.verdict.split(':').next().unwrap_or("")
        );
        body += &format!(
            "\n## {}. {}\n\nMeasurement file: `{}`. Models: {}.\n\n",
            k + 1,
            c.title,
            c.file,
            c.models
                .iter()
                .map(|m| format!("`{m}`"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        body += &markdown(&d);
        body += "\nFigures:\n\n";
        for f in figs {
            let rel = f.strip_prefix(base_dir).unwrap_or(&f);
            body += &format!(
                "![{}]({})\n",
                f.file_stem().unwrap_or_default().to_string_lossy(),
                rel.display()
            );
        }
    }
    let text = format!(
        "# Diagnosing a missing effect: fifteen synthetic cases\n\n\
         Regenerate with\n\n```\ncargo run --release -- bench diagnose --report {}\n```\n\n\
         (seconds: no DEM; {} TMCMC samples per stage, seed {}).\n\n{}\n\n\
         ## Summary\n\n{summary}\n{body}",
        a.report.display(),
        a.samples,
        a.seed,
        HOW
    );
    write_atomic(&a.report, text.as_bytes())?;
    crate::report_written(
        a.json,
        &a.report,
        serde_json::json!({ "seed": a.seed, "samples": a.samples }),
    );
    Ok(())
}

const HOW: &str = "How the data were made. The measurement files hold mbgc DEM runs of the \
shear box per sieve fraction (d50 2, 4, 8 and 16 mm, sigma_ln 0.12, box scale 10, campaign seed \
11), the tables in `docs/data/diagnose/`: a material of spheres with E = 5 MPa, nu 0.3, e 0.5, \
mu_pp 0.5, mu_pw 0.3, mu_r_pp 0.3 and rho_p 2600 kg/m3, and the hidden effect switched on in the \
runs but not in the class the file compares with. Cases 1 and 3-5 give each fraction as the mean \
of three runs with sd = the pooled replicate sd / sqrt(3) (the replicate sd of one run is \
1.8-1.9 deg and 2.8-5.3 kg/m3 here); case 2 gives one run per fraction with sd 1.06 deg and \
3.8 kg/m3 (the replicate noise of docs/metamodel.md). The model error is each model's \
validation RMSE (or its error model's value at the fit). That RMSE holds one run's DEM noise \
as well, which a measured value's sd already holds; where a model records its replicate noise \
(the shipped ones do), only its miss beyond that noise counts, and it is shared between the \
samples with correlation 0.8 (the model misses one material alike at each size). The local \
models record none: their whole error counts, independent between the samples, so their chi^2 \
is conservative. A model of a class with an extra effect serves the class without it where that effect \
is off (rolling friction or cohesion 0). The column `(xN)` is the ratio of the interval's ends.\n\n\
Cases 6-9 (issue 35) are another material, E = 4.5 MPa, in five fractions of 1-16 mm (the \
4e4 J/m3 set in four, 2-16 mm: at 1 mm nothing flows out of the box), with mu_pp and mu_r_pp \
both unknown, made by `docs/data/diagnose/issue35/make_sets.sh` (seed 35, three runs per \
fraction), and compared with the shipped global models alone (`mbgc diagnose`'s default: \
`models/shear_box.json` and its cohesive extension `models/shear_box_sjkr.json`, \
docs/metamodel_sjkr.md). Their truth is mu_pp 0.5 and mu_r_pp 0.3, checked in the fit of the \
class the data were made with.\n\n\
Cases 10-12 (issue 40) are fine materials of the same frictions without cohesion, in three \
fractions of 0.5-2 mm, at three stiffnesses and densities (E 5, 20 and 50 MPa; rho_p 1000, 2600 \
and 1500 kg/m3), made by `docs/data/diagnose/issue40/make_sets.sh` (seed 40, three runs per \
fraction). Their K_p = E / (rho_p g d50), 2.5e5 to 6.8e6, lies beyond the shipped base \
model's training runs (9.8e3-1.94e5): it answers by its rigid limit (docs/rigid_limit.md), \
with the limit's scatter in its error. So does the cohesive model (docs/rigid_limit_sjkr.md), \
which reads its cohesion there at C_pp (E*_edge / E*)^(2/3), the cohesion a contact on its \
stiffness edge pulls with (docs/cohesion_stiffness.md).\n\n\
Cases 13-15 (issue 40) are the materials of cases 10 and 11 with a hidden cohesion between the \
particles (walls not cohesive): ced_pp 1e4 and 2.5e4 J/m3, read at the edge as C_pp 430-680 \
and 310-490 of the model's 0-978, and 1.4e4 J/m3 on the material of case 10 (600-950). The \
same six sets diagnosed with the widened pair (`models/shear_box_wide.json`, \
`models/shear_box_sjkr_wide.json`) are in docs/metamodel_wide.md.\n\n\
The models. Cases 1, 3 and 4 (rolling friction known, 0.3) use two versions of a local model \
around the material, its known values fixed (recorded in the model files as constants). Version \
1, `models/diagnose_local.json`, is the class without cohesion (`mbgc train --space \
examples/space_diagnose_local.toml --experiment shear-box --name diagnose_local --n 16 \
--validation 6 --max-length 16 --parsimony 0.01`: mu_pp and d50 varied, 22 runs). Version 2, \
`models/diagnose_local_sjkr.json`, was made from it by adding the effect the diagnosis of \
version 1 names (`mbgc train --space examples/space_diagnose_local_sjkr.toml --experiment \
shear-box --name diagnose_local_sjkr --extends diagnose_local --n 40 --validation 10 \
--max-length 24 --parsimony 0.003`): the space gains ced_pp in [0, 3e4] J/m3, version 1's 22 \
runs are copied onto its ced_pp = 0 face, and only the 28 new rows of the sequentially extended \
design were simulated (272 s on 2 cores). The error ladder of these cases is version 1 -> \
version 2. Cases 2 and 5 (rolling friction searched) use the shipped global model \
(`models/shear_box.json`) for the class with rolling friction and a local model of the class \
with cohesion and rolling friction (`models/shear_box_cohesion_local.json`, space \
`examples/space_cohesion_local.toml`: mu_pp, mu_r_pp, ced_pp and d50 varied).\n\n\
The loop of case 1, as a user runs it:\n\n\
```\n\
# 1. compare version 1 with the measurements: chi^2/dof 6.86, an offset in the shear angle, and\n\
#    sjkr, the one candidate, not evaluated for want of a model\n\
mbgc diagnose --measurements examples/measurements/hidden_cohesion_strong.toml \\\n    \
--model models/diagnose_local.json\n\
# 2. add the effect: only the new rows are simulated\n\
mbgc train --space examples/space_diagnose_local_sjkr.toml --experiment shear-box \\\n    \
--name diagnose_local_sjkr --extends diagnose_local --n 40 --validation 10 \\\n    \
--max-length 24 --parsimony 0.003\n\
# 3. diagnose again with both versions: the ranking, the strength, the ladder 1 -> 2\n\
mbgc diagnose --measurements examples/measurements/hidden_cohesion_strong.toml \\\n    \
--model models/diagnose_local.json --model models/diagnose_local_sjkr.json --plot figs\n\
```";
