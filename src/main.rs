//! The `dormant` binary: everything is in the library's `cli` module.

fn main() -> std::process::ExitCode {
    dormant::cli::main()
}
