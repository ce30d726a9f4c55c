//! The command line's report (stdout) and messages (stderr), written so
//! that a closed pipe or a full disk is an error to report, never a panic
//! (`println!` panics on EPIPE and ENOSPC).
//!
//! [`out`] writes one line to stdout; the first failure is kept and every
//! later line is dropped (nobody reads them). The command ends by asking
//! [`stdout_failure`], which flushes what is buffered and returns the error,
//! so that the CLI prints one line on stderr and exits
//! [`EXIT_STDOUT`](crate::run::EXIT_STDOUT) (docs/guide.md §12). [`err`]
//! writes one line to stderr and ignores a failure: there is nowhere left
//! to report it, and the exit code still says what happened.

use std::fmt::Arguments;
use std::io::Write;
use std::sync::Mutex;

/// The first error of a write to stdout (the text of the `io::Error`).
static FAILED: Mutex<Option<String>> = Mutex::new(None);

fn failed() -> std::sync::MutexGuard<'static, Option<String>> {
    FAILED.lock().unwrap_or_else(|p| p.into_inner())
}

/// Writes one line (`args` and a newline) to stdout; after a failure,
/// nothing (the failure is kept for [`stdout_failure`]).
pub fn out(args: Arguments<'_>) {
    let mut f = failed();
    if f.is_some() {
        return;
    }
    let mut o = std::io::stdout().lock();
    if let Err(e) = o.write_fmt(args).and_then(|()| o.write_all(b"\n")) {
        *f = Some(e.to_string());
    }
}

/// Writes one line to stderr, ignoring a failure (a closed or full stderr).
pub fn err(args: Arguments<'_>) {
    let mut e = std::io::stderr().lock();
    let _ = e.write_fmt(args).and_then(|()| e.write_all(b"\n"));
}

/// Flushes stdout; the first error of any write to it so far (None: every
/// line was written).
pub fn stdout_failure() -> Option<String> {
    let mut f = failed();
    if f.is_none() {
        if let Err(e) = std::io::stdout().lock().flush() {
            *f = Some(e.to_string());
        }
    }
    f.clone()
}

/// Records a failed write to stdout made elsewhere (clap's help text).
pub fn record_stdout_failure(e: &std::io::Error) {
    let mut f = failed();
    if f.is_none() {
        *f = Some(e.to_string());
    }
}

/// `println!` that never panics: [`out`].
#[macro_export]
macro_rules! outln {
    ($($t:tt)*) => { $crate::io::console::out(format_args!($($t)*)) };
}

/// `eprintln!` that never panics: [`err`].
#[macro_export]
macro_rules! errln {
    ($($t:tt)*) => { $crate::io::console::err(format_args!($($t)*)) };
}
