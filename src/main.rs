use clap::Parser;

fn main() {
    // Threads for faer's dense/supernodal kernels: SIGNORINI_THREADS=1 runs
    // sequentially (the default is faer's: all cores, via rayon).
    if let Some(t) = std::env::var("SIGNORINI_THREADS")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        faer::set_global_parallelism(if t <= 1 {
            faer::Par::Seq
        } else {
            faer::Par::rayon(t)
        });
    }
    let cli = signorini::cli::Cli::parse();
    std::process::exit(signorini::cli::run(cli));
}
