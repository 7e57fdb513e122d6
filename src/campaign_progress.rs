//! The campaign's progress bar on standard error (hidden when it is not a terminal): the
//! command line's observer of [`mbgc::campaign::run_campaign`].

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mbgc::campaign::{Observer, ObserverHandle};

struct Bar(ProgressBar);

impl Observer for Bar {
    fn started(&self, to_run: usize, already_done: usize) {
        self.0.set_length(to_run as u64);
        if already_done > 0 {
            self.0
                .set_message(format!("(+{already_done} already done) "));
        }
        self.0.reset_elapsed();
        // Hidden until now, so a campaign with nothing left to run draws no empty bar.
        self.0.set_draw_target(ProgressDrawTarget::stderr());
    }

    fn run_recorded(&self, _failed: bool) {
        self.0.inc(1);
    }

    fn ended(&self, completed: bool) {
        if completed {
            self.0.finish();
        } else {
            self.0.abandon();
        }
    }
}

/// A bar that appears when the campaign has runs to make.
pub fn bar() -> ObserverHandle {
    let bar = ProgressBar::hidden();
    if let Ok(style) = ProgressStyle::with_template(
        "{elapsed_precise} [{wide_bar}] {pos}/{len} runs {msg}({per_sec}, ETA {eta})",
    ) {
        bar.set_style(style.progress_chars("=> "));
    }
    ObserverHandle::new(Bar(bar))
}

/// Tells that `run_campaign` added response columns to the table at `out`.
pub fn note_added_columns(out: &std::path::Path, s: &mbgc::campaign::Summary) {
    if let Some(note) = s.added_columns_note(out) {
        eprintln!("{note}");
    }
}
