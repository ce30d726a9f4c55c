//! One loop for every iterative method (the `argmin` pattern): a method
//! implements one iteration ([`Iterative::step`]); the [`Executor`] owns the
//! MAXIT test, NaN/stagnation guards, the iteration log and the observers
//! (the caller's progress display among them, [`ProgressDisplay`]).

use crate::qp::{Failure, IterRecord, Status};
use std::time::Instant;

/// What one iteration reports.
pub enum Step {
    /// Keep going; the record is logged.
    Continue(IterRecord),
    /// The method has finished (converged, unbounded, failed).
    Done(Status, IterRecord),
}

pub trait Iterative {
    fn step(&mut self) -> Step;

    /// The iterate of the last [`Iterative::step`] has the best residual so
    /// far: a method that can return to it keeps it (default: nothing).
    fn best(&mut self) {}

    /// The run stagnated: go back to the iterate of the last
    /// [`Iterative::best`] call, which the method then returns (its
    /// residual stood below the last one's; default: nothing).
    fn back_to_best(&mut self) {}
}

/// Sees every iteration record.
pub trait Observer {
    fn observe(&mut self, rec: &IterRecord);
    fn finish(&mut self) {}
}

/// The caller's display of a solve's progress (the command line's spinner
/// on stderr, `cli::progress`): it makes a fresh [`Observer`] of each
/// executor's iterations. Only the display may read the clock; no decision
/// of a method depends on it.
pub trait ProgressDisplay: Send + Sync + std::fmt::Debug {
    /// The observer of the iterations of `label` (the caller's label, or
    /// the method's name), made when its executor is.
    fn start(&self, label: &str) -> Box<dyn Observer>;
}

/// Iterations without a new best residual (by a relative 1e-9) after which
/// a run is stopped as stagnating: far longer than any plateau of the
/// methods here (CGC faces, MPRGP expansions), far shorter than MAXIT.
pub const STALL_WINDOW: usize = 10_000;

pub struct Executor {
    pub max_iter: usize,
    pub observers: Vec<Box<dyn Observer>>,
    pub log: Vec<IterRecord>,
    /// Keep at most this many log records (the first and last are kept).
    pub log_limit: usize,
    /// Stop when this instant has passed (a user's time budget).
    pub deadline: Option<Instant>,
    /// Stop when this flag is non-zero (the caller's cancel,
    /// [`crate::qp::SolveOptions::stop`]).
    pub stop: Option<&'static std::sync::atomic::AtomicI32>,
}

impl Executor {
    /// An executor of at most `max_iter` iterations, observed by `progress`
    /// (a [`ProgressDisplay`]'s observer) if any.
    pub fn new(max_iter: usize, progress: Option<Box<dyn Observer>>) -> Executor {
        Executor {
            max_iter,
            observers: progress.into_iter().collect(),
            log: vec![],
            log_limit: 10_000,
            deadline: None,
            stop: None,
        }
    }

    /// Run `it` until it finishes or MAXIT; returns the status and the
    /// number of iterations done.
    pub fn run(&mut self, it: &mut dyn Iterative) -> (Status, usize) {
        let mut n = 0;
        let mut best = f64::INFINITY;
        let mut best_at = 0;
        let status = loop {
            if n >= self.max_iter {
                break Status::MaxIter;
            }
            if let Some(flag) = self.stop {
                let signal = flag.load(std::sync::atomic::Ordering::Relaxed);
                if signal != 0 {
                    break Status::Failed(Failure::Interrupted {
                        signal,
                        iterations: n,
                    });
                }
            }
            if let Some(d) = self.deadline {
                let now = Instant::now();
                if now >= d {
                    break Status::Failed(Failure::TimeLimit { iterations: n });
                }
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
                break Status::Failed(Failure::NotFinite { iteration: n });
            }
            // −0 (a sum over no rows) is 0; a zero residual the method
            // does not stop at measured nothing (a projected gradient with
            // every row on its bound) and is no best a later iterate can
            // be held to: the dual method, started exactly, stagnated
            // against a best of −0 for 10 000 iterations.
            if rec.residual == 0.0 {
                rec.residual = 0.0;
            }
            let measured = done.is_some() || rec.residual > 0.0;
            if measured && rec.residual < best * (1.0 - 1e-9) {
                best = rec.residual;
                best_at = n;
                if done.is_none() {
                    it.best();
                }
            }
            let res = rec.residual;
            for o in self.observers.iter_mut() {
                o.observe(&rec);
            }
            self.push(rec);
            if let Some(s) = done {
                break s;
            }
            if n - best_at >= STALL_WINDOW {
                it.back_to_best();
                break Status::Failed(Failure::Stagnation {
                    residual: res,
                    best,
                    best_at,
                    window: STALL_WINDOW,
                });
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

#[cfg(test)]
mod tests {
    use super::*;

    struct Flat(usize);
    impl Iterative for Flat {
        fn step(&mut self) -> Step {
            self.0 += 1;
            Step::Continue(IterRecord {
                iter: 0,
                residual: 1.0 + (self.0 % 2) as f64,
                active: 0,
                inner: 0,
            })
        }
    }

    struct Nan;
    impl Iterative for Nan {
        fn step(&mut self) -> Step {
            Step::Continue(IterRecord {
                iter: 0,
                residual: f64::NAN,
                active: 0,
                inner: 0,
            })
        }
    }

    #[test]
    fn stagnation_and_nan_are_failures_maxit_is_maxit() {
        let (s, n) = Executor::new(1_000_000, None).run(&mut Flat(0));
        assert!(
            matches!(&s, Status::Failed(Failure::Stagnation { best_at: 2, .. })),
            "{s:?}"
        );
        // The best (1.0) is reached at iteration 2.
        assert_eq!(n, STALL_WINDOW + 2);
        let (s, n) = Executor::new(100, None).run(&mut Flat(0));
        assert!(matches!(s, Status::MaxIter) && n == 100, "{s:?}");
        let (s, n) = Executor::new(100, None).run(&mut Nan);
        assert!(
            matches!(&s, Status::Failed(Failure::NotFinite { iteration: 1 })) && n == 1,
            "{s:?}"
        );
    }

    /// −0 first (a projected gradient over no free row), then a residual
    /// that falls to 0.5 at iteration 50 and stops there.
    struct ZeroFirst(usize);
    impl Iterative for ZeroFirst {
        fn step(&mut self) -> Step {
            self.0 += 1;
            let r = |residual| IterRecord {
                iter: 0,
                residual,
                active: 0,
                inner: 0,
            };
            match self.0 {
                1 => Step::Continue(r(-0.0)),
                k if k < 50 => Step::Continue(r(1.0 - k as f64 * 0.01)),
                _ => Step::Continue(r(0.5)),
            }
        }
    }

    /// A zero residual the method goes on from is no best: the run
    /// stagnates against the best it measured (0.5 at iteration 50), not
    /// against −0 at iteration 1, and the log holds +0.
    #[test]
    fn a_zero_the_method_goes_on_from_is_no_best() {
        let mut e = Executor::new(1_000_000, None);
        let (s, n) = e.run(&mut ZeroFirst(0));
        match &s {
            Status::Failed(Failure::Stagnation { best, best_at, .. }) => {
                assert_eq!(*best_at, 50, "{s:?}");
                assert_eq!(*best, 0.5, "{s:?}");
            }
            _ => panic!("{s:?}"),
        }
        assert_eq!(n, STALL_WINDOW + 50);
        assert!(e.log[0].residual.is_sign_positive() && e.log[0].residual == 0.0);
    }
}
