//! The `fmi-fuzz` command line as a library module, so that `main.rs` only parses, dispatches
//! and maps the outcome to an exit code, and the parsing can be unit-tested: the options
//! ([`Cli`]) and one module per command, each with its options and its driver.

pub mod cycles;
pub mod fuzz;
pub mod worker;

use clap::{Parser, Subcommand};

/// The options of the default command (fuzzing) are flattened into the top level, so
/// `fmi-fuzz --fmu X.fmu` fuzzes; the subcommands exclude them.
#[derive(Parser)]
#[command(
    name = "fmi-fuzz",
    about = "State-machine fuzzer and memory cycles for FMI 2.0 co-simulation FMUs",
    args_conflicts_with_subcommands = true
)]
pub struct Cli {
    /// A subcommand; none means fuzzing with the top-level options.
    #[command(subcommand)]
    pub command: Option<Cmd>,
    /// The fuzzing options, used when there is no subcommand.
    #[command(flatten)]
    pub fuzz: fuzz::FuzzArgs,
}

/// The commands besides fuzzing.
#[derive(Subcommand)]
pub enum Cmd {
    /// Instantiate/initialize/step/FMU-state/free cycles (run this under valgrind).
    Cycles(cycles::CyclesArgs),
    /// Runs sequences in this process and prints the child protocol (used by the runner).
    #[command(hide = true)]
    Worker(worker::WorkerArgs),
}

/// `--preset name=value`, both sides trimmed.
pub fn parse_preset(s: &str) -> Result<(String, String), String> {
    s.split_once('=')
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .ok_or_else(|| format!("expected name=value, got {s:?}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::error::ErrorKind;
    use std::path::PathBuf;

    fn parse(args: &[&str]) -> Result<Cli, clap::Error> {
        Cli::try_parse_from(std::iter::once("fmi-fuzz").chain(args.iter().copied()))
    }

    #[test]
    fn fuzz_options_and_their_defaults() {
        let cli = parse(&["--fmu", "a.fmu", "--fmu", "b.fmu", "--preset", " x = 1 "]).unwrap();
        assert!(cli.command.is_none());
        let a = cli.fuzz;
        assert_eq!(a.fmus, [PathBuf::from("a.fmu"), PathBuf::from("b.fmu")]);
        assert_eq!(a.presets, [("x".to_string(), "1".to_string())]);
        assert_eq!(
            (a.sequences, a.seed, a.max_len, a.batch),
            (1000, 1, 40, 2000)
        );
        assert_eq!((a.preset_percent, a.mem_limit_mb, a.show), (90, 4096, 3));
        assert_eq!(
            (a.timeout, a.jobs, a.max_failures, a.trace),
            (60.0, None, 0, false)
        );
    }

    #[test]
    fn cycles_and_worker_options() {
        let cli = parse(&[
            "cycles",
            "--fmu",
            "a.fmu",
            "--cycles",
            "5",
            "--step-size",
            "0.5",
        ]);
        let Some(Cmd::Cycles(c)) = cli.unwrap().command else {
            panic!("not cycles")
        };
        assert_eq!((c.cycles, c.steps, c.step_size), (5, 10, 0.5));
        let cli = parse(&[
            "worker", "--fmu", "a.fmu", "--first", "7", "--count", "2", "--trace",
        ]);
        let Some(Cmd::Worker(w)) = cli.unwrap().command else {
            panic!("not worker")
        };
        assert_eq!(
            (w.first, w.count, w.max_len, w.preset_percent),
            (7, 2, 40, 90)
        );
        assert!(w.trace);
    }

    #[test]
    fn bad_command_lines_are_refused() {
        let kind = |args: &[&str]| parse(args).err().map(|e| e.kind());
        assert_eq!(kind(&["--bogus"]), Some(ErrorKind::UnknownArgument));
        assert_eq!(kind(&["--sequences"]), Some(ErrorKind::InvalidValue));
        assert_eq!(
            kind(&["--sequences", "-3"]),
            Some(ErrorKind::UnknownArgument)
        );
        assert_eq!(
            kind(&["--sequences", "many"]),
            Some(ErrorKind::ValueValidation)
        );
        assert_eq!(kind(&["--preset", "abc"]), Some(ErrorKind::ValueValidation));
        // Fuzz options do not mix with a subcommand.
        assert_eq!(
            kind(&["--fmu", "a.fmu", "cycles"]),
            Some(ErrorKind::ArgumentConflict)
        );
        assert_eq!(
            kind(&["worker", "--fmu", "a.fmu"]),
            Some(ErrorKind::MissingRequiredArgument)
        );
    }

    #[test]
    fn preset_needs_an_equals_sign() {
        assert_eq!(parse_preset("a=b=c").unwrap(), ("a".into(), "b=c".into()));
        assert!(parse_preset("abc").unwrap_err().contains("name=value"));
    }
}
