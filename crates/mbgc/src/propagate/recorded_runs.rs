//! The finished runs of a propagation as the bands read them: each run's values of the
//! experiment's responses and the event it had ([`Experiment::event_of`]), if any.

use crate::experiments::Experiment;

/// The runs of a design, in design-row order.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedRuns {
    /// The experiment's responses, the order of each run's values.
    names: Vec<&'static str>,
    /// Each event and what it leaves without a value ([`Experiment::voided_by`]).
    voided: Vec<(&'static str, Vec<&'static str>)>,
    /// Per design row: `None` until the run finished, else its event and values.
    runs: Vec<Option<(Option<&'static str>, Vec<f64>)>>,
}

impl RecordedRuns {
    /// From `runs[r]`, design row r's recorded values of `experiment.responses()` in that order
    /// (NaN for one the run lacks), `None` for a row that has not finished.
    pub fn new(experiment: &dyn Experiment, runs: Vec<Option<Vec<f64>>>) -> RecordedRuns {
        let names = experiment.responses();
        let runs = runs
            .into_iter()
            .map(|r| {
                r.map(|v| {
                    let value = |n: &str| {
                        names
                            .iter()
                            .position(|m| *m == n)
                            .and_then(|i| v.get(i).copied())
                    };
                    (experiment.event_of(&value), v)
                })
            })
            .collect();
        RecordedRuns {
            names,
            voided: experiment
                .events()
                .into_iter()
                .map(|e| (e, experiment.voided_by(e)))
                .collect(),
            runs,
        }
    }

    /// `response` of every design row: NaN for a row that has not finished or lacks it, and for
    /// a response an event voids, of a run that had one (a table written before the
    /// experiment voided such runs itself still holds a number there).
    pub fn values(&self, response: &str) -> Vec<f64> {
        let i = self.names.iter().position(|n| *n == response);
        let voids = |event: &Option<&str>| {
            event.is_some_and(|e| {
                self.voided
                    .iter()
                    .any(|(name, list)| *name == e && list.contains(&response))
            })
        };
        self.runs
            .iter()
            .map(|r| match (r, i) {
                (Some((event, v)), Some(i)) if !voids(event) => {
                    v.get(i).copied().unwrap_or(f64::NAN)
                }
                _ => f64::NAN,
            })
            .collect()
    }

    /// Finished runs, and how many had each event that happened at all (in the experiment's
    /// order): what a reader of one point's runs (the best fit's) must be told, since a run an
    /// event voided drops out of that point's value.
    pub fn event_counts(&self) -> (usize, Vec<(&'static str, usize)>) {
        let finished = self.runs.iter().flatten().count();
        let counts = self
            .voided
            .iter()
            .map(|(e, _)| {
                let k = self
                    .runs
                    .iter()
                    .flatten()
                    .filter(|(x, _)| *x == Some(*e))
                    .count();
                (*e, k)
            })
            .filter(|(_, k)| *k > 0)
            .collect();
        (finished, counts)
    }

    /// Per draw (`seeds` consecutive rows each), whether each of its finished runs had `event`.
    pub fn event_by_draw(&self, event: &str, seeds: usize) -> Vec<Vec<bool>> {
        self.runs
            .chunks(seeds.max(1))
            .map(|c| c.iter().flatten().map(|(e, _)| *e == Some(event)).collect())
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiments::hopper::Hopper;

    /// A row of the hopper's responses with the flow rate, the top angle and the discharged
    /// fraction set.
    fn hopper_row(h: &Hopper, flow: f64, top: f64, fraction: f64) -> Vec<f64> {
        h.responses()
            .iter()
            .map(|n| match *n {
                "flow_rate" => flow,
                "repose_angle_top" => top,
                "discharged_fraction" => fraction,
                "arch_held" => 0.0,
                _ => 1.0,
            })
            .collect()
    }

    /// A clogged run written before the hopper voided clogs (a finite flow rate at 3 % of the
    /// fill discharged) loses its measured quantities but keeps its diagnostics; an unfinished
    /// row has nothing and no event.
    #[test]
    fn a_clogged_run_of_an_old_table_is_voided_and_counted() {
        let h = Hopper {
            class: Default::default(),
        };
        let runs = RecordedRuns::new(
            &h,
            vec![
                Some(hopper_row(&h, 2.8, 40.0, 0.42)),
                Some(hopper_row(&h, 0.97, 30.0, 0.03)),
                None,
                Some(hopper_row(&h, 2.5, 44.0, 0.37)),
            ],
        );
        let flow = runs.values("flow_rate");
        assert_eq!(flow[0], 2.8);
        assert!(flow[1].is_nan() && flow[2].is_nan());
        assert_eq!(flow[3], 2.5);
        assert!(runs.values("repose_angle_top")[1].is_nan());
        assert!(runs.values("beverloo_ratio")[1].is_nan());
        assert!(runs.values("repose_angle_bottom_4")[1].is_nan());
        assert_eq!(runs.values("beverloo_ratio")[0], 1.0);
        assert_eq!(runs.values("discharged_fraction")[1], 0.03);
        assert!(runs.values("no_such_response").iter().all(|v| v.is_nan()));
        assert_eq!(
            runs.event_by_draw("clogged", 2),
            vec![vec![false, true], vec![false]]
        );
        assert_eq!(runs.event_counts(), (3, vec![("clogged", 1)]));
    }

    /// A discharge that stalled and restarted (the binned rates of row 22 of the gravel
    /// propagation, docs/data/propagation/gravel/hopper/runs.csv) loses its flow rate and
    /// Beverloo's ratio, not its angles; each event voids only its own list.
    #[test]
    fn an_intermittent_run_loses_its_flow_rate_only() {
        let h = Hopper {
            class: Default::default(),
        };
        let mut stalled = hopper_row(&h, 0.45, 33.0, 0.28);
        let row22 = [1.02, 0.41, 0.24, 0.87, 1.22, 1.07, 0.55, 0.37];
        for (name, v) in crate::experiments::hopper::FLOW_BIN_NAMES.iter().zip(row22) {
            let i = h.responses().iter().position(|n| n == name).unwrap();
            stalled[i] = v;
        }
        let runs = RecordedRuns::new(
            &h,
            vec![
                Some(stalled),
                Some(hopper_row(&h, 0.97, 30.0, 0.03)),
                Some(hopper_row(&h, 2.5, 44.0, 0.37)),
            ],
        );
        let flow = runs.values("flow_rate");
        assert!(flow[0].is_nan() && flow[1].is_nan());
        assert_eq!(flow[2], 2.5);
        assert!(runs.values("beverloo_ratio")[0].is_nan());
        assert_eq!(runs.values("repose_angle_top")[0], 33.0);
        assert!(runs.values("repose_angle_top")[1].is_nan());
        assert_eq!(
            runs.event_by_draw("intermittent", 1),
            vec![vec![true], vec![false], vec![false]]
        );
        assert_eq!(
            runs.event_counts(),
            (3, vec![("clogged", 1), ("intermittent", 1)])
        );
    }

    /// Row 8 of the gravel propagation (docs/data/propagation/gravel/hopper_poured): the flow
    /// stopped at 8.8 % of the fill with 86 particles held over the orifice. It loses its flow
    /// rate and its angles as a clog does; a run of a table without the count (NaN) has no late
    /// clog.
    #[test]
    fn a_late_arch_is_a_late_clog_voided_as_a_clog() {
        let h = Hopper {
            class: Default::default(),
        };
        let held = h
            .responses()
            .iter()
            .position(|n| *n == "arch_held")
            .unwrap();
        let mut late = hopper_row(&h, 1.6, 35.0, 0.088);
        late[held] = 86.0;
        let mut old = late.clone();
        old[held] = f64::NAN;
        let mut early = hopper_row(&h, 0.9, 30.0, 0.03);
        early[held] = 120.0;
        let runs = RecordedRuns::new(
            &h,
            vec![
                Some(late),
                Some(old),
                Some(early),
                Some(hopper_row(&h, 2.5, 44.0, 0.37)),
            ],
        );
        let flow = runs.values("flow_rate");
        assert_eq!((flow[1], flow[3]), (1.6, 2.5));
        assert!(flow[0].is_nan() && flow[2].is_nan());
        assert!(runs.values("beverloo_ratio")[0].is_nan());
        let top = runs.values("repose_angle_top");
        assert!(top[0].is_nan() && top[2].is_nan());
        assert_eq!((top[1], top[3]), (35.0, 44.0));
        assert!(runs.values("repose_angle_bottom_2")[0].is_nan());
        assert_eq!(
            runs.event_counts(),
            (4, vec![("clogged", 1), ("clogged_late", 1)])
        );
    }
}
