//! Experiments by command-line name.

use super::sleep_test::SleepTest;
use crate::dem::experiments::hopper::Hopper;
use crate::dem::experiments::shear_box::ShearBox;
use crate::dem::experiments::wall_impact::WallImpact;
use crate::dem::experiments::Experiment;
use crate::error::{Error, Result};

/// Campaign-wide settings that experiments may read when they are built. Experiments that have
/// no use for a setting ignore it (wall-impact ignores all of them).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ExperimentSettings {
    /// `--box-scale k`: size of the experiment's box relative to its default (shear box, hopper).
    pub box_scale: Option<f64>,
}

impl ExperimentSettings {
    pub fn validate(&self) -> Result<()> {
        match self.box_scale {
            Some(k) if !(k.is_finite() && k > 0.0) => Err(Error::invalid(format!(
                "--box-scale {k}: expected a positive finite factor"
            ))),
            _ => Ok(()),
        }
    }
}

type Constructor = fn(&ExperimentSettings) -> Result<Box<dyn Experiment>>;

/// Every experiment the command line knows. Registering one is one line here.
const EXPERIMENTS: &[(&str, Constructor)] = &[
    ("wall-impact", |_| Ok(Box::new(WallImpact::default()))),
    ("hopper", |_| Ok(Box::new(Hopper))),
    ("shear-box", |s| {
        Ok(Box::new(ShearBox {
            box_scale: s.box_scale.unwrap_or(ShearBox::default().box_scale),
            ..ShearBox::default()
        }))
    }),
];

/// Stand-ins for the tests of the campaign machinery, only known when this variable is `1`.
pub const TEST_EXPERIMENTS_ENV: &str = "MBGC_TEST_EXPERIMENTS";

const TEST_EXPERIMENTS: &[(&str, Constructor)] = &[("sleep-test", |_| Ok(Box::new(SleepTest)))];

/// Names accepted by [`experiment_by_name`] (without the hidden test experiments).
pub fn experiment_names() -> Vec<&'static str> {
    EXPERIMENTS.iter().map(|(n, _)| *n).collect()
}

/// The experiment called `name` on the command line, built with `settings`.
pub fn experiment_by_name(
    name: &str,
    settings: &ExperimentSettings,
) -> Result<Box<dyn Experiment>> {
    let with_tests = std::env::var(TEST_EXPERIMENTS_ENV).is_ok_and(|v| v == "1");
    lookup(name, settings, with_tests)
}

fn lookup(
    name: &str,
    settings: &ExperimentSettings,
    with_tests: bool,
) -> Result<Box<dyn Experiment>> {
    settings.validate()?;
    let tests: &[(&str, Constructor)] = if with_tests { TEST_EXPERIMENTS } else { &[] };
    match EXPERIMENTS.iter().chain(tests).find(|(n, _)| *n == name) {
        Some((_, make)) => make(settings),
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
            assert_eq!(lookup(name, &s, false).unwrap().name(), name);
        }
        let e = lookup("shear-bx", &s, false).err().unwrap().to_string();
        assert!(
            e.contains("--experiment shear-bx") && e.contains("wall-impact"),
            "{e}"
        );
        assert!(lookup("sleep-test", &s, false).is_err());
        assert_eq!(lookup("sleep-test", &s, true).unwrap().name(), "sleep-test");
    }

    #[test]
    fn bad_box_scale_is_refused_naming_the_option() {
        for k in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let s = ExperimentSettings { box_scale: Some(k) };
            let e = lookup("wall-impact", &s, false).err().unwrap().to_string();
            assert!(e.contains("--box-scale"), "{e}");
        }
        let s = ExperimentSettings {
            box_scale: Some(1.5),
        };
        assert!(lookup("wall-impact", &s, false).is_ok());
    }
}
