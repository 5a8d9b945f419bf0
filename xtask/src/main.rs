//! Project automation, run as `cargo xtask <command>` (an alias in .cargo/config.toml):
//!
//! - `fmu`: build the FMU crates in release and package `<target>/fmu/<modelIdentifier>.fmu`;
//! - `test [--rust-only | --python-only] [-- <pytest args>]`: packaging, cargo fmt --check,
//!   cargo doc with warnings denied, cargo test, the Python harness (tests/, run with pytest in
//!   `.venv`, created on demand), clippy's and rustc's warnings of every build denied (the builds
//!   run clippy's driver: `lints.rs`), and a summary;
//! - `demo [-- <study args>]`: package the FMUs, run the standard case, the paper's studies and
//!   the estimator variants with `alignment-studies` (the studies on top of the orchestrator),
//!   then the fleet, and print the headline table.
//!
//! Exit codes: 0 success; 1 a failure (a test stage, a demo step, a bad option of a command);
//! 2 no command or an unknown one (the usage on stderr).

mod binaries;
mod cli;
mod demo;
mod fmus;
mod headline;
mod headline_curves;
mod lints;
mod package;
mod progress;
mod python;
mod test;
mod workspace;

use cli::{Command, USAGE};
use std::process::ExitCode;

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match cli::parse(&args) {
        Ok(Command::Fmu) => package::build_and_package(workspace::Profile::Release).map(|_| true),
        Ok(Command::Test(o)) => test::test(o),
        Ok(Command::Demo(extra)) => demo::demo(extra).map(|_| true),
        Ok(Command::Help) => {
            println!("{USAGE}");
            Ok(true)
        }
        Ok(Command::Usage) => {
            eprintln!("{USAGE}");
            return ExitCode::from(2);
        }
        Err(e) => Err(e),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::FAILURE
        }
    }
}
