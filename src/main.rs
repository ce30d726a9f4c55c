use clap::Parser;
use std::alloc::{GlobalAlloc, Layout, System};

/// The system allocator, except that running out of memory ends the process
/// with exit code 2 and one `error:` line saying how much was asked for,
/// instead of an abort (SIGABRT). The message is formatted on the stack:
/// nothing may be allocated at that point.
struct ExitOnOom;

fn out_of_memory(size: usize) -> ! {
    use std::fmt::Write;
    struct Buf {
        b: [u8; 320],
        n: usize,
    }
    impl Write for Buf {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            let k = s.len().min(self.b.len() - self.n);
            self.b[self.n..self.n + k].copy_from_slice(&s.as_bytes()[..k]);
            self.n += k;
            Ok(())
        }
    }
    let mut m = Buf { b: [0; 320], n: 0 };
    let gib = size as f64 / (1u64 << 30) as f64;
    let _ = if gib >= 0.01 {
        writeln!(
            m,
            "error: out of memory: an allocation of {gib:.2} GiB failed; this problem needs about {gib:.2} GiB more than the memory available (RAM, ulimit -v)"
        )
    } else {
        writeln!(
            m,
            "error: out of memory: an allocation of {:.1} kiB failed: the memory (RAM, ulimit -v) is exhausted",
            size as f64 / 1024.0
        )
    };
    // SAFETY: write(2) and _exit(2) on a valid buffer; no allocation, no unwinding.
    unsafe {
        libc::write(2, m.b.as_ptr().cast(), m.n);
        libc::_exit(2)
    }
}

// SAFETY: every call is forwarded to `System` unchanged; a null result ends
// the process instead of being returned.
unsafe impl GlobalAlloc for ExitOnOom {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(l) };
        if p.is_null() {
            out_of_memory(l.size());
        }
        p
    }
    unsafe fn alloc_zeroed(&self, l: Layout) -> *mut u8 {
        let p = unsafe { System.alloc_zeroed(l) };
        if p.is_null() {
            out_of_memory(l.size());
        }
        p
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, new: usize) -> *mut u8 {
        let q = unsafe { System.realloc(p, l, new) };
        if q.is_null() {
            out_of_memory(new);
        }
        q
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
}

#[global_allocator]
static ALLOC: ExitOnOom = ExitOnOom;

fn main() {
    // SIGNORINI_THREADS=t: rayon's worker threads (faer's kernels, the
    // assembly, the multigrid); t = 1 also makes the assembly sequential
    // (read here only, passed down). The bits do not depend on it: faer's
    // kernels split their work the same way on any count
    // (`signorini::linalg::PAR_SPLITS`).
    let threads = std::env::var("SIGNORINI_THREADS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok());
    // Start rayon's worker threads now, where a failure (thread stacks beyond
    // `ulimit -v`) can be reported: rayon would panic at first use. One
    // thread is tried when the default count cannot be started.
    let count = threads.unwrap_or(0);
    if rayon::ThreadPoolBuilder::new()
        .num_threads(count)
        .build_global()
        .is_err()
    {
        if let Err(e) = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build_global()
        {
            signorini::errln!(
                "error: out of memory: cannot start a worker thread ({e}); raise the memory limit (ulimit -v)"
            );
            std::process::exit(2);
        }
    }
    signorini::linalg::fix_parallelism();
    // clap's own answers (`--help`, `--version`, a refused flag) with a
    // checked stdout: a closed pipe is exit 4, not a silent 0.
    let mut cli = match signorini::cli::Cli::try_parse() {
        Ok(c) => c,
        Err(e) => std::process::exit(signorini::cli::clap_exit(&e)),
    };
    cli.build.parallel = threads.is_none_or(|t| t > 1);
    std::process::exit(signorini::cli::run(cli));
}
