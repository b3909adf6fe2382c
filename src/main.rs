//! The `dormant` binary: the command line ([`cli`]), which wires the renderer library
//! (`dormant`) and the lab (`dormant_lab`) together, and the plot of a run's statistics
//! ([`report`]).

mod cli;
mod report;

fn main() -> std::process::ExitCode {
    cli::main()
}
