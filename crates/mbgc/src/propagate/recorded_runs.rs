//! The finished runs of a propagation as the bands read them: each run's values of the
//! experiment's responses and the event it had ([`Experiment::event_of`]), if any.

use crate::experiments::Experiment;

/// The runs of a design, in design-row order.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedRuns {
    /// The experiment's responses, the order of each run's values.
    names: Vec<&'static str>,
    /// What an event leaves without a value ([`Experiment::voided_by_events`]).
    voided: Vec<&'static str>,
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
            voided: experiment.voided_by_events(),
            runs,
        }
    }

    /// `response` of every design row: NaN for a row that has not finished or lacks it, and for
    /// a response an event voids, of a run that had one (a table written before the
    /// experiment voided such runs itself still holds a number there).
    pub fn values(&self, response: &str) -> Vec<f64> {
        let i = self.names.iter().position(|n| *n == response);
        let void = self.voided.contains(&response);
        self.runs
            .iter()
            .map(|r| match (r, i) {
                (Some((event, v)), Some(i)) if !(void && event.is_some()) => {
                    v.get(i).copied().unwrap_or(f64::NAN)
                }
                _ => f64::NAN,
            })
            .collect()
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
    }
}
