//! `divertsim`: the command-line entry point; see `divertsim --help`.

use clap::Parser;

fn main() {
    let cli = divertsim::cli::Cli::parse();
    let code = divertsim::cli::run(cli);
    // Whatever a failed command claimed and did not publish.
    divertsim::outdir::release_all();
    std::process::exit(code);
}
