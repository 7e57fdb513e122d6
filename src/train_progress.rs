//! The command line's view of a train (`mbgc train`, and the local models of
//! `mbgc diagnose --build`): stage news on standard error, a bar per campaign and one for the fit.

use std::cell::RefCell;
use std::path::Path;

use indicatif::{ProgressBar, ProgressStyle};

use mbgc::campaign::ObserverHandle;
use mbgc::train::{TrainObserver, TrainStage};

/// The command line's view of a train: each stage's news on standard error, a bar per campaign
/// and one for the fit's generations.
pub(crate) struct Printer {
    pub(crate) bar: ProgressBar,
    current: RefCell<String>,
}

impl Printer {
    pub(crate) fn new(generations: usize) -> Printer {
        let bar = ProgressBar::hidden();
        bar.set_length(generations as u64);
        bar.set_style(
            ProgressStyle::with_template("[3/3 fit] {prefix:>14} [{bar:30}] gen {pos}/{len} {msg}")
                .expect("static template")
                .progress_chars("=> "),
        );
        Printer {
            bar,
            current: RefCell::new(String::new()),
        }
    }
}

impl TrainObserver for Printer {
    fn note(&self, stage: TrainStage, text: &str) {
        eprintln!("[{stage}] {text}");
    }

    fn campaign(&self, _table: &Path) -> Option<ObserverHandle> {
        Some(crate::campaign_progress::bar())
    }

    fn fit_progress(&self, response: &str, p: &mbgc::gp::Progress) {
        let mut current = self.current.borrow_mut();
        if *current != response {
            if current.is_empty() {
                self.bar
                    .set_draw_target(indicatif::ProgressDrawTarget::stderr());
            }
            *current = response.to_string();
            self.bar.reset();
            self.bar.set_prefix(current.clone());
        }
        self.bar.set_position(p.generation as u64 + 1);
        self.bar.set_message(format!("1-R2 {:.3e}", p.best_nmse));
    }
}
