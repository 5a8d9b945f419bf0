//! `fmi-fuzz`: hostile-caller checks for FMI 2.0 co-simulation FMUs.
//!
//! ```text
//! fmi-fuzz --fmu target/fmu/AlignmentEstimator.fmu --sequences 100000 --seed 1
//! fmi-fuzz --fmu X.fmu --seed 1234 --sequences 1 --trace      # replay one seed, every call
//! fmi-fuzz cycles --fmu X.fmu --cycles 1000                     # run under valgrind
//! ```
//!
//! Exit codes: 0 every check passed; 1 a fuzz sequence failed (the report says which seeds);
//! 2 anything else: a bad command line, an FMU that cannot be loaded, a cycle that went wrong.
//! Each command is a module of [`fmi_fuzz::cli`].

use clap::Parser;
use fmi_fuzz::cli::{Cli, Cmd, cycles, fuzz, worker};
use std::process::ExitCode;

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Some(Cmd::Worker(a)) => worker::worker(a),
        Some(Cmd::Cycles(a)) => cycles::cycles(a),
        None => fuzz::fuzz(cli.fuzz),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("fmi-fuzz: {e:#}");
            ExitCode::from(2)
        }
    }
}
