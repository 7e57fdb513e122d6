//! `sleep-test`: a stand-in experiment for the tests of the campaign machinery (kill and resume,
//! failures, panics). It is never part of a binary users build: `campaign` includes this file
//! only under `#[cfg(test)]` or the `stand-ins` feature, which only `cargo test` switches on
//! (through the root package's dev-dependency on `mbgc` with that feature).
//!
//! Parameters: `x` in [-1e6, 1e6], `y` in [0, 1e6] (negative `y` is "impossible", to test
//! [`Experiment::check`]), optional `sleep_ms` (default 0), `fail`, `panic` and `no_value` (a
//! value >= 0.5 makes the run return an error, panic, or measure `f` as NaN). Responses: `f = x + 2 y` and `noise`, the row seed
//! mapped to [0, 1), which shows that seeds reach the experiment. A transient failure (one that a
//! retry can cure): the run with `x` equal to the environment variable `SLEEP_TEST_FAIL_X` fails.

use std::time::Duration;

use mbgc::error::{Error, Result};
use mbgc::experiments::{Diagnostics, Experiment, Outcome, ParamSet, RunOptions};

#[derive(Debug, Clone, Copy, Default)]
pub struct SleepTest;

struct Inputs {
    x: f64,
    y: f64,
    sleep_ms: f64,
    fail: bool,
    panic: bool,
    no_value: bool,
}

fn inputs(p: &ParamSet) -> Result<Inputs> {
    Ok(Inputs {
        x: p.require("x", -1e6, 1e6)?,
        y: p.require("y", 0.0, 1e6)?,
        sleep_ms: p.optional("sleep_ms", 0.0, 0.0, 60_000.0)?,
        fail: p.optional("fail", 0.0, 0.0, 1.0)? >= 0.5,
        panic: p.optional("panic", 0.0, 0.0, 1.0)? >= 0.5,
        no_value: p.optional("no_value", 0.0, 0.0, 1.0)? >= 0.5,
    })
}

impl Experiment for SleepTest {
    fn name(&self) -> &'static str {
        "sleep-test"
    }

    fn parameters(&self) -> Vec<&'static str> {
        vec!["x", "y"]
    }

    fn optional_parameters(&self) -> Vec<&'static str> {
        vec!["sleep_ms", "fail", "panic", "no_value"]
    }

    fn responses(&self) -> Vec<&'static str> {
        vec!["f", "noise"]
    }

    fn check(&self, p: &ParamSet) -> Result<()> {
        inputs(p).map(|_| ())
    }

    fn run(&self, p: &ParamSet, seed: u64, _opts: &RunOptions) -> Result<Outcome> {
        let i = inputs(p)?;
        std::thread::sleep(Duration::from_secs_f64(i.sleep_ms * 1e-3));
        if i.panic {
            panic!("sleep-test: panic on request at x = {}", i.x);
        }
        let transient = std::env::var("SLEEP_TEST_FAIL_X")
            .ok()
            .and_then(|v| v.parse::<f64>().ok())
            == Some(i.x);
        if transient {
            return Err(Error::invalid(format!(
                "sleep-test: transient failure at x = {}",
                i.x
            )));
        }
        if i.fail {
            // Comma, quotes and a newline: the table must keep the message intact.
            return Err(Error::invalid(format!(
                "sleep-test: \"fail\" requested, x = {},\nsecond line",
                i.x
            )));
        }
        Ok(Outcome {
            responses: vec![
                (
                    "f".into(),
                    if i.no_value {
                        f64::NAN
                    } else {
                        i.x + 2.0 * i.y
                    },
                ),
                ("noise".into(), seed as f64 / 18_446_744_073_709_551_616.0),
            ],
            diagnostics: Diagnostics {
                settled: i.x >= 0.0,
                steps: i.sleep_ms as u64,
                particles: 1,
                // Nominal rather than measured, so that test tables are reproducible to the byte.
                wall_time_s: i.sleep_ms * 1e-3,
                warnings: if i.x < 0.0 {
                    vec!["x < 0, not settled".into()]
                } else {
                    vec![]
                },
            },
        })
    }
}
