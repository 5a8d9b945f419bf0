#![allow(clippy::result_large_err)]
//! The `orchestrator` command line. See `orchestrator --help` and `docs/orchestrator.md`; each
//! command is a module of [`orchestrator::cli`].
//!
//! Exit codes: 0 success; 1 an I/O failure (results cannot be written, or the output is refused
//! by the output policy, [`orchestrator::outdir`] and [`orchestrator::outfile`]); 2 bad input (a
//! file, the system description, a connection, a parameter, the command line, a run over
//! `--max-output-size`); 3 an FMU failed during
//! the run (results recorded until then are kept); 130 `run` or `simulate` interrupted by
//! Ctrl-C (SIGINT), SIGTERM or SIGHUP: the run stops at the next step boundary and keeps the
//! results recorded until then (a second signal quits at once, leaving `results.csv.partial`).

use clap::{Parser, Subcommand};
use orchestrator::cli::{self, export, info, run, simulate};
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "orchestrator",
    version,
    about = "A fast, strict FMI 2.0 co-simulation master"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a system described in SSP (.ssd or .ssp).
    Run(run::RunArgs),
    /// Run one FMU, optionally with input signals from a CSV file (like `fmpy simulate`).
    Simulate(simulate::SimulateArgs),
    /// Describe an FMU: identity, capabilities, default experiment and variables (like `fmpy info`).
    Info(info::InfoArgs),
    /// Write a system as an .ssp archive with its FMUs, which other masters (libcosim,
    /// OMSimulator, fmpy) can run.
    ExportSsp(export::ExportArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match &cli.command {
        Command::Run(a) => run::stop_on_interrupt(&a.settings.common.interrupt),
        Command::Simulate(a) => run::stop_on_interrupt(&a.common.interrupt),
        Command::Info(_) | Command::ExportSsp(_) => {}
    }
    let result = match &cli.command {
        Command::Run(a) => {
            run::run(a).map(|done| eprintln!("{}", cli::summary_text(&done.summary)))
        }
        Command::Simulate(a) => {
            simulate::simulate(a).map(|s| eprintln!("{}", cli::summary_text(&s)))
        }
        Command::Info(a) => info::info(a).map(|text| print!("{text}")),
        Command::ExportSsp(a) => {
            export::export_ssp(a).map(|()| eprintln!("wrote {}", a.out.display()))
        }
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(e.exit_code() as u8)
        }
    }
}
