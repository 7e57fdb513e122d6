//! Run ids and per-row seeds: pure functions of a row's inputs, so every machine, shard and
//! restart names and seeds a row the same way.

use super::registry::ExperimentSettings;
use crate::experiments::shear_box::RestRule;
use crate::experiments::ParamSet;
use crate::numeric::{splitmix64, Fnv1a};
use mbgc_dem::contact::ModelClass;

/// The id of a run: 64-bit FNV-1a over the experiment name, each input's name and the bits of its
/// value (so `0.0` and `-0.0` differ, and a value re-read from a CSV matches only if it is the same
/// number), the row seed, and the settings that can change results (`box_scale`, only when given;
/// the model class, only when it is not seed 004's default, so that the ids of tables written
/// before model classes existed, all of the default class, stay valid; the backend, only when
/// it is not the embedded engine, and the rest rule, only when it is not the kinetic one, for
/// the same reason), printed as 16 lowercase hex digits. The
/// number of MPI processes (`--mpi`) is an execution setting, like the threads: it is recorded
/// in the table's sidecar, and a table holds the runs of one process count.
pub fn run_id(
    experiment: &str,
    inputs: &ParamSet,
    seed: u64,
    settings: &ExperimentSettings,
    class: Option<&ModelClass>,
) -> String {
    let mut h = Fnv1a::default();
    h.str(experiment);
    for (name, value) in inputs.iter() {
        h.str(name);
        h.u64(value.to_bits());
    }
    h.u64(seed);
    if let Some(k) = settings.box_scale {
        h.str("box_scale");
        h.u64(k.to_bits());
    }
    if let Some(c) = class.filter(|c| **c != ModelClass::default()) {
        h.str("model_class");
        h.str(&c.label());
    }
    if let Some(r) = settings.rest_rule.filter(|r| *r != RestRule::Kinetic) {
        h.str("rest_rule");
        h.str(&r.label());
    }
    if settings.backend.is_recorded() {
        h.str("backend");
        h.str(settings.backend.label());
    }
    format!("{:016x}", h.0)
}
/// The seed of design row `row` (0-based) in a campaign with seed `seed`:
/// `splitmix64(splitmix64(seed) ^ row)`. It depends on nothing else, so a row is reproducible on
/// its own (any shard, any thread, any restart), and for a given campaign seed no two rows share
/// a seed (both steps are bijections).
pub fn row_seed(seed: u64, row: u64) -> u64 {
    splitmix64(splitmix64(seed) ^ row)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inputs(v: f64) -> ParamSet {
        ParamSet::from_pairs(&[("a", 1.5), ("b", v)])
    }

    #[test]
    fn run_id_is_stable_and_sensitive_to_every_part() {
        let s = ExperimentSettings::default();
        let id = run_id("wall-impact", &inputs(2.0), 7, &s, None);
        assert_eq!(id.len(), 16);
        assert!(id.chars().all(|c| c.is_ascii_hexdigit()));
        // Golden value: a run id must never change between versions, or resumes would rerun.
        assert_eq!(id, run_id("wall-impact", &inputs(2.0), 7, &s, None));
        assert_eq!(id, "d6be556de2e938d2");
        let others = [
            run_id("shear-box", &inputs(2.0), 7, &s, None),
            run_id(
                "wall-impact",
                &inputs(2.0 + f64::EPSILON * 2.0),
                7,
                &s,
                None,
            ),
            run_id("wall-impact", &inputs(2.0), 8, &s, None),
            run_id(
                "wall-impact",
                &ParamSet::from_pairs(&[("b", 2.0), ("a", 1.5)]),
                7,
                &s,
                None,
            ),
            run_id(
                "wall-impact",
                &inputs(2.0),
                7,
                &ExperimentSettings {
                    box_scale: Some(2.0),
                    ..Default::default()
                },
                None,
            ),
        ];
        for o in others {
            assert_ne!(o, id);
        }
        // The default class, given or not, keeps the id; another class changes it.
        let default = ModelClass::default();
        assert_eq!(
            run_id("wall-impact", &inputs(2.0), 7, &s, Some(&default)),
            id
        );
        let cohesive = ModelClass::parse("hertz,mindlin,epsd2,sjkr").unwrap();
        assert_ne!(
            run_id("wall-impact", &inputs(2.0), 7, &s, Some(&cohesive)),
            id
        );
        let liggghts = ExperimentSettings {
            backend: crate::campaign::Backend::Liggghts,
            ..Default::default()
        };
        let l1 = run_id("wall-impact", &inputs(2.0), 7, &liggghts, None);
        assert_ne!(l1, id);
        let on = |n| ExperimentSettings {
            mpi: Some(n),
            ..liggghts
        };
        assert_eq!(run_id("wall-impact", &inputs(2.0), 7, &on(1), None), l1);
        assert_eq!(run_id("wall-impact", &inputs(2.0), 7, &on(2), None), l1);
        // The kinetic rule, given or not, keeps the id (every table before issue 38 was run by
        // it); the response rule changes it.
        let rule = |r| ExperimentSettings {
            rest_rule: Some(r),
            ..Default::default()
        };
        let kinetic = rule(RestRule::Kinetic);
        assert_eq!(run_id("wall-impact", &inputs(2.0), 7, &kinetic, None), id);
        let response = rule(RestRule::CANDIDATE);
        assert_ne!(run_id("wall-impact", &inputs(2.0), 7, &response, None), id);
        assert_ne!(
            run_id("x", &inputs(0.0), 1, &s, None),
            run_id("x", &inputs(-0.0), 1, &s, None)
        );
    }

    #[test]
    fn row_seeds_are_distinct_and_depend_on_the_campaign_seed() {
        let mut seen = std::collections::HashSet::new();
        for row in 0..10_000 {
            assert!(seen.insert(row_seed(1, row)));
        }
        assert_ne!(row_seed(1, 0), row_seed(2, 0));
        assert_eq!(row_seed(1, 5), row_seed(1, 5));
    }
}
