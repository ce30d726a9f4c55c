//! The command line's progress display ([`ProgressDisplay`]): a spinner
//! (indicatif) on stderr for solves longer than one second, with the
//! iteration, residual, active-set size and inner iterations. indicatif
//! draws nothing when stderr is not a terminal; `-q` installs no display.

use crate::qp::{IterRecord, Observer, ProgressDisplay};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The progress display of a command: spinners, or none with `-q`.
pub fn progress(quiet: bool) -> Option<Arc<dyn ProgressDisplay>> {
    (!quiet).then(|| Arc::new(Spinners) as Arc<dyn ProgressDisplay>)
}

/// Makes a [`Spinner`] for each executor of a solve.
#[derive(Debug, Clone, Copy, Default)]
pub struct Spinners;

impl ProgressDisplay for Spinners {
    fn start(&self, label: &str) -> Box<dyn Observer> {
        Box::new(Spinner {
            start: Instant::now(),
            name: label.to_string(),
            bar: None,
        })
    }
}

/// One executor's spinner, shown from its first iteration after one
/// second (the clock decides the display only).
pub struct Spinner {
    start: Instant,
    name: String,
    bar: Option<indicatif::ProgressBar>,
}

impl Observer for Spinner {
    fn observe(&mut self, rec: &IterRecord) {
        if self.bar.is_none() && self.start.elapsed() > Duration::from_secs(1) {
            let bar = indicatif::ProgressBar::new_spinner();
            if let Ok(style) =
                indicatif::ProgressStyle::with_template("{spinner} {prefix} [{elapsed}] {msg}")
            {
                bar.set_style(style);
            }
            bar.set_prefix(self.name.clone());
            bar.enable_steady_tick(Duration::from_millis(200));
            self.bar = Some(bar);
        }
        if let Some(bar) = &self.bar {
            bar.set_message(format!(
                "iteration {}  residual {:.3e}  active {}  inner {}",
                rec.iter, rec.residual, rec.active, rec.inner
            ));
        }
    }
    fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}
