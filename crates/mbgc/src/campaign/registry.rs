//! Experiments by command-line name.

use super::backend::Backend;
use crate::error::{Error, Result};
use crate::experiments::clogging_silo::ClogSilo;
use crate::experiments::hopper::Hopper;
use crate::experiments::shear_box::{RestRule, ShearBox};
use crate::experiments::shear_cell::ShearCell;
use crate::experiments::wall_impact::WallImpact;
use crate::experiments::Experiment;
use crate::liggghts::shear_box_experiment::{DeckMode, LiggghtsShearBox};
use crate::liggghts::shear_cell_experiment::LiggghtsShearCell;
use mbgc_dem::contact::ModelClass;
use std::sync::Mutex;

/// Campaign-wide settings that experiments may read when they are built. An experiment that has
/// no use for a setting given refuses it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExperimentSettings {
    /// `--box-scale k`: size of the experiment's box relative to its default (shear box, hopper).
    pub box_scale: Option<f64>,
    /// `--model-class`: the effects of the contact law (default: seed 004's class).
    pub model_class: Option<ModelClass>,
    /// `--backend`: the code that simulates (part of each run's identity).
    pub backend: Backend,
    /// `--mpi N`: MPI processes per run of an external backend. LIGGGHTS repeats a run exactly
    /// on the same N, not on another (the domain decomposition reorders the force sums and the
    /// granular flow amplifies it), so a table records its N in the sidecar and holds runs of
    /// one N; the run id names the physical run and leaves N out, as it leaves out the threads.
    pub mpi: Option<usize>,
    /// `--rest-rule`: when a shear-box run's fill and outflow are at rest (default: the kinetic
    /// rule of every campaign before issue 38). Part of a run's identity when not kinetic.
    pub rest_rule: Option<RestRule>,
}

impl ExperimentSettings {
    /// Refuses a non-positive or non-finite box scale, zero MPI processes, and `--mpi` with the
    /// embedded engine.
    pub fn validate(&self) -> Result<()> {
        if let Some(k) = self.box_scale {
            if !(k.is_finite() && k > 0.0) {
                return Err(Error::invalid(format!(
                    "--box-scale {k}: expected a positive finite factor"
                )));
            }
        }
        if let Some(r) = self.rest_rule {
            r.check()
                .map_err(|e| Error::invalid(format!("--rest-rule: {e}")))?;
        }
        match (self.mpi, self.backend) {
            (Some(0), _) => Err(Error::invalid("--mpi 0: expected at least 1 process")),
            (Some(n), Backend::Embedded) => Err(Error::invalid(format!(
                "--mpi {n}: the embedded backend does not use MPI (it runs one run per thread, \
                 --threads), so it would do nothing; use it with --backend liggghts"
            ))),
            _ => Ok(()),
        }
    }
}

/// The LIGGGHTS form of an experiment, for `mode`; an experiment without a LIGGGHTS deck is
/// refused by name.
fn liggghts_experiment(
    name: &str,
    s: &ExperimentSettings,
    mode: DeckMode,
) -> Result<Box<dyn Experiment>> {
    match name {
        "shear-box" => Ok(Box::new(LiggghtsShearBox::new(
            ShearBox {
                box_scale: s.box_scale.unwrap_or(ShearBox::default().box_scale),
                class: s.model_class.unwrap_or_default(),
                rest: s.rest_rule.unwrap_or_default(),
                ..ShearBox::default()
            },
            mode,
        )?)),
        "shear-cell" => {
            no_rest_rule("shear-cell", s)?;
            Ok(Box::new(LiggghtsShearCell::new(
                ShearCell {
                    cell_scale: s.box_scale.unwrap_or(ShearCell::default().cell_scale),
                    class: s.model_class.unwrap_or_default(),
                    ..ShearCell::default()
                },
                mode,
            )?))
        }
        _ if all().iter().any(|(n, _)| *n == name) => Err(Error::invalid(format!(
            "--experiment {name} --backend liggghts: mbgc writes LIGGGHTS decks for the shear box \
             and the shear cell only; run {name} with the embedded backend"
        ))),
        _ => Err(Error::invalid(format!(
            "--experiment {name}: unknown experiment (known: {})",
            experiment_names().join(", ")
        ))),
    }
}

/// The experiment `name` that reads back runs made from decks written by `--write-decks`
/// (`mbgc campaign import`).
pub fn experiment_for_import(
    name: &str,
    settings: &ExperimentSettings,
) -> Result<Box<dyn Experiment>> {
    settings.validate()?;
    if settings.backend != Backend::Liggghts {
        return Err(Error::invalid(format!(
            "importing runs needs an external backend, found {}",
            settings.backend
        )));
    }
    liggghts_experiment(
        name,
        settings,
        DeckMode::Import {
            ranks: settings.mpi.unwrap_or(1),
        },
    )
}

/// Refuses `--box-scale` for an experiment that would ignore it.
fn no_box_scale(name: &str, s: &ExperimentSettings, why: &str) -> Result<()> {
    match s.box_scale {
        Some(k) => Err(Error::invalid(format!(
            "--box-scale {k}: {name} does not read it ({why}), so it would do nothing"
        ))),
        None => Ok(()),
    }
}

/// Refuses `--rest-rule` for an experiment that has no rest rule to set.
fn no_rest_rule(name: &str, s: &ExperimentSettings) -> Result<()> {
    match s.rest_rule {
        Some(r) => Err(Error::invalid(format!(
            "--rest-rule {}: {name} has no rest rule (only the shear box ends its phases by \
             one), so it would do nothing",
            r.label()
        ))),
        None => Ok(()),
    }
}

/// The box scale an experiment runs at when `given` is what the command line said: the shear
/// box's own default when none was given; `None` for experiments without a box scale.
pub fn effective_box_scale(experiment: &str, given: Option<f64>) -> Option<f64> {
    match experiment {
        "shear-box" => Some(given.unwrap_or(ShearBox::default().box_scale)),
        "shear-cell" => Some(given.unwrap_or(ShearCell::default().cell_scale)),
        _ => given,
    }
}

/// Builds an experiment from the campaign-wide settings.
pub type Constructor = fn(&ExperimentSettings) -> Result<Box<dyn Experiment>>;

/// Every experiment the command line knows. Registering one is one line here.
const EXPERIMENTS: &[(&str, Constructor)] = &[
    ("wall-impact", |s| {
        no_box_scale("wall-impact", s, "it has no box")?;
        no_rest_rule("wall-impact", s)?;
        Ok(Box::new(WallImpact {
            class: s.model_class.unwrap_or_default(),
        }))
    }),
    ("hopper", |s| {
        no_box_scale("hopper", s, "its size is the `scale` parameter")?;
        no_rest_rule("hopper", s)?;
        Ok(Box::new(Hopper {
            class: s.model_class.unwrap_or_default(),
        }))
    }),
    ("clogging-silo", |s| {
        no_box_scale("clogging-silo", s, "its size is in particle diameters")?;
        no_rest_rule("clogging-silo", s)?;
        Ok(Box::new(ClogSilo {
            class: s.model_class.unwrap_or_default(),
        }))
    }),
    ("shear-box", |s| {
        Ok(Box::new(ShearBox {
            box_scale: s.box_scale.unwrap_or(ShearBox::default().box_scale),
            class: s.model_class.unwrap_or_default(),
            rest: s.rest_rule.unwrap_or_default(),
            ..ShearBox::default()
        }))
    }),
    ("shear-cell", |s| {
        no_rest_rule("shear-cell", s)?;
        Ok(Box::new(ShearCell {
            cell_scale: s.box_scale.unwrap_or(ShearCell::default().cell_scale),
            class: s.model_class.unwrap_or_default(),
            ..ShearCell::default()
        }))
    }),
];

/// The test stand-in experiment, from `tests/stand_ins/`.
#[cfg(any(test, feature = "stand-ins"))]
#[path = "../../tests/stand_ins/sleep_test.rs"]
pub(crate) mod sleep_test;

/// Test stand-ins, compiled only into test builds (`stand-ins` feature, see Cargo.toml).
#[cfg(feature = "stand-ins")]
const STAND_INS: &[(&str, Constructor)] = &[("sleep-test", |s| {
    no_rest_rule("sleep-test", s)?;
    Ok(Box::new(sleep_test::SleepTest))
})];
#[cfg(not(feature = "stand-ins"))]
const STAND_INS: &[(&str, Constructor)] = &[];

/// Experiments added at run time by a program that embeds mbgc (its own experiment, or the test
/// stand-ins), before it calls `mbgc_cli::main`.
static REGISTERED: Mutex<Vec<(&'static str, Constructor)>> = Mutex::new(Vec::new());

/// Built-in experiments, then the stand-ins (test builds only), then the registered ones.
fn all() -> Vec<(&'static str, Constructor)> {
    // A poisoned lock only means another thread panicked while pushing; the list is still valid.
    let registered = REGISTERED.lock().unwrap_or_else(|e| e.into_inner());
    EXPERIMENTS
        .iter()
        .chain(STAND_INS)
        .chain(registered.iter())
        .copied()
        .collect()
}

/// Makes `name` known to [`experiment_by_name`] (and so to `mbgc simulate --experiment`).
/// A name that is already taken is refused.
pub fn register(name: &'static str, make: Constructor) -> Result<()> {
    let mut list = REGISTERED.lock().unwrap_or_else(|e| e.into_inner());
    if EXPERIMENTS
        .iter()
        .chain(STAND_INS)
        .chain(list.iter())
        .any(|(n, _)| *n == name)
    {
        return Err(Error::invalid(format!(
            "experiment {name}: already registered (expected a new name)"
        )));
    }
    list.push((name, make));
    Ok(())
}

/// Names accepted by [`experiment_by_name`]: the built-in experiments, then the registered ones.
pub fn experiment_names() -> Vec<&'static str> {
    all().iter().map(|(n, _)| *n).collect()
}

/// The experiment called `name` on the command line, built with `settings`.
pub fn experiment_by_name(
    name: &str,
    settings: &ExperimentSettings,
) -> Result<Box<dyn Experiment>> {
    settings.validate()?;
    if settings.backend == Backend::Liggghts {
        let ranks = settings.mpi.unwrap_or(1);
        return liggghts_experiment(name, settings, DeckMode::Run { ranks });
    }
    match all().into_iter().find(|(n, _)| *n == name) {
        Some((_, make)) => {
            let e = make(settings)?;
            if let (Some(c), None) = (settings.model_class, e.class()) {
                return Err(Error::invalid(format!(
                    "--model-class {c}: {name} has no contact law, so the class would do nothing"
                )));
            }
            Ok(e)
        }
        None => Err(Error::invalid(format!(
            "--experiment {name}: unknown experiment (known: {})",
            experiment_names().join(", ")
        ))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve_and_unknown_names_are_refused_with_the_list() {
        let s = ExperimentSettings::default();
        for name in experiment_names() {
            assert_eq!(experiment_by_name(name, &s).unwrap().name(), name);
        }
        let e = experiment_by_name("shear-bx", &s)
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.contains("--experiment shear-bx") && e.contains("wall-impact"),
            "{e}"
        );
        // Registering makes a name known (the constructor decides what is built); taking a
        // known name is refused.
        assert!(experiment_by_name("embedded", &s).is_err());
        register("embedded", |_| Ok(Box::new(WallImpact::default()))).unwrap();
        assert_eq!(
            experiment_by_name("embedded", &s).unwrap().name(),
            "wall-impact"
        );
        assert!(experiment_names().contains(&"embedded"));
        let e = register("shear-box", |_| Ok(Box::new(WallImpact::default())));
        assert!(e.unwrap_err().to_string().contains("already registered"));
    }

    #[test]
    fn the_rest_rule_reaches_the_shear_box_and_is_refused_where_nothing_reads_it() {
        let response = ExperimentSettings {
            rest_rule: Some(RestRule::parse("response").unwrap()),
            ..Default::default()
        };
        let e = experiment_by_name("shear-box", &response).unwrap();
        assert_eq!(e.name(), "shear-box");
        for name in ["wall-impact", "hopper", "shear-cell"] {
            let e = experiment_by_name(name, &response)
                .err()
                .unwrap()
                .to_string();
            assert!(
                e.contains("--rest-rule response") && e.contains(name),
                "{e}"
            );
        }
        let liggghts = ExperimentSettings {
            backend: Backend::Liggghts,
            ..response
        };
        let e = experiment_by_name("shear-box", &liggghts)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("kinetic rule only"), "{e}");
        // An unknown name is refused with the known ones.
        let e = RestRule::parse("calm").unwrap_err();
        assert!(
            e.contains("\"calm\"") && e.contains("kinetic, response"),
            "{e}"
        );
        assert_eq!(RestRule::parse("kinetic").unwrap().label(), "kinetic");
        assert_eq!(RestRule::CANDIDATE.label(), "response");
    }

    #[test]
    fn bad_box_scale_is_refused_naming_the_option() {
        for k in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let s = ExperimentSettings {
                box_scale: Some(k),
                ..Default::default()
            };
            let e = experiment_by_name("wall-impact", &s)
                .err()
                .unwrap()
                .to_string();
            assert!(e.contains("--box-scale"), "{e}");
        }
        let s = ExperimentSettings {
            box_scale: Some(1.5),
            ..Default::default()
        };
        assert!(experiment_by_name("shear-box", &s).is_ok());
        for name in ["wall-impact", "hopper"] {
            let e = experiment_by_name(name, &s).err().unwrap().to_string();
            assert!(e.contains("--box-scale 1.5") && e.contains(name), "{e}");
        }
    }
}
