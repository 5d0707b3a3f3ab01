//! `divertsim`: the command-line entry point; see `divertsim --help`.

use clap::Parser;

fn main() {
    let cli = divertsim::cli::Cli::parse();
    std::process::exit(divertsim::cli::run(cli));
}
