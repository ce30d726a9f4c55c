//! One loop for every iterative method (the `argmin` pattern): a method
//! implements one iteration ([`Iterative::step`]); the [`Executor`] owns the
//! MAXIT test, NaN/stagnation guards, the iteration log and progress output.

use super::{IterRecord, Status};
use std::time::{Duration, Instant};

/// What one iteration reports.
pub enum Step {
    /// Keep going; the record is logged.
    Continue(IterRecord),
    /// The method has finished (converged, unbounded, failed).
    Done(Status, IterRecord),
}

pub trait Iterative {
    fn step(&mut self) -> Step;
}

/// Sees every iteration record.
pub trait Observer {
    fn observe(&mut self, rec: &IterRecord);
    fn finish(&mut self) {}
}

/// A progress bar (indicatif) on stderr for solves longer than one second:
/// iteration, residual, active-set size, inner iterations. Hidden when stderr
/// is not a terminal.
pub struct Progress {
    start: Instant,
    name: String,
    bar: Option<indicatif::ProgressBar>,
}

impl Progress {
    pub fn new(name: &str) -> Progress {
        Progress {
            start: Instant::now(),
            name: name.to_string(),
            bar: None,
        }
    }
}

impl Observer for Progress {
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

pub struct Executor {
    pub max_iter: usize,
    pub observers: Vec<Box<dyn Observer>>,
    pub log: Vec<IterRecord>,
    /// Keep at most this many log records (the first and last are kept).
    pub log_limit: usize,
}

impl Executor {
    pub fn new(max_iter: usize, progress: Option<&str>) -> Executor {
        let mut observers: Vec<Box<dyn Observer>> = vec![];
        if let Some(name) = progress {
            observers.push(Box::new(Progress::new(name)));
        }
        Executor {
            max_iter,
            observers,
            log: vec![],
            log_limit: 10_000,
        }
    }

    /// Run `it` until it finishes or MAXIT; returns the status and the
    /// number of iterations done.
    pub fn run(&mut self, it: &mut dyn Iterative) -> (Status, usize) {
        let mut n = 0;
        let status = loop {
            if n >= self.max_iter {
                break Status::MaxIter;
            }
            n += 1;
            let (rec, done) = match it.step() {
                Step::Continue(r) => (r, None),
                Step::Done(s, r) => (r, Some(s)),
            };
            let mut rec = rec;
            rec.iter = n;
            if !rec.residual.is_finite() && done.is_none() {
                self.push(rec);
                break Status::Failed(format!("NaN or Inf in iteration {n}"));
            }
            for o in self.observers.iter_mut() {
                o.observe(&rec);
            }
            self.push(rec);
            if let Some(s) = done {
                break s;
            }
        };
        for o in self.observers.iter_mut() {
            o.finish();
        }
        (status, n)
    }

    fn push(&mut self, rec: IterRecord) {
        if self.log.len() >= self.log_limit {
            self.log.pop();
        }
        self.log.push(rec);
    }
}
