use clap::Parser;

fn main() {
    let cli = signorini::cli::Cli::parse();
    std::process::exit(signorini::cli::run(cli));
}
