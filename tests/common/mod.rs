//! Helpers shared by integration tests that run the `signorini` binary.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// How one run of the binary ended.
#[derive(Debug, Clone)]
pub struct Run {
    /// Exit code; `None` when the process was killed (budget) or died by a signal.
    pub code: Option<i32>,
    /// Killed because it outlived its budget.
    pub hung: bool,
    /// Wall time of the run (reported only; no decision depends on it but the kill).
    pub secs: f64,
    /// Standard output and error, concatenated.
    pub output: String,
}

/// Run `signorini ARGS` with a time budget: the child is killed when it
/// outlives `budget`, so a hanging method cannot hang the test. Output goes
/// to files in `scratch` (no pipe can fill up and block the child).
pub fn run_signorini(args: &[String], budget: Duration, scratch: &Path) -> Run {
    std::fs::create_dir_all(scratch).expect("scratch directory");
    let out_path = scratch.join("stdout.txt");
    let err_path = scratch.join("stderr.txt");
    let stdout = std::fs::File::create(&out_path).expect("stdout file");
    let stderr = std::fs::File::create(&err_path).expect("stderr file");
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_signorini"))
        .args(args)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .expect("start signorini");
    let mut hung = false;
    let status = loop {
        if let Some(s) = child.try_wait().expect("wait for signorini") {
            break Some(s);
        }
        if start.elapsed() > budget {
            let _ = child.kill();
            let _ = child.wait();
            hung = true;
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let output = format!(
        "{}{}",
        std::fs::read_to_string(&out_path).unwrap_or_default(),
        std::fs::read_to_string(&err_path).unwrap_or_default()
    );
    Run {
        code: status.and_then(|s| s.code()),
        hung,
        secs: start.elapsed().as_secs_f64(),
        output,
    }
}
