//! `fmi-fuzz`: hostile-caller checks for FMI 2.0 co-simulation FMUs.
//!
//! ```text
//! fmi-fuzz --fmu target/fmu/AlignmentEstimator.fmu --sequences 100000 --seed 1
//! fmi-fuzz --fmu X.fmu --seed 1234 --sequences 1 --trace      # replay one seed, every call
//! fmi-fuzz cycles --fmu X.fmu --cycles 1000                     # run under valgrind
//! ```

use anyhow::{Result, bail};
use clap::{Args, Parser, Subcommand};
use fmi_fuzz::fuzz::{Config, Trace};
use fmi_fuzz::runner::{self, RunOptions};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

#[derive(Parser)]
#[command(
    name = "fmi-fuzz",
    about = "State-machine fuzzer and memory cycles for FMI 2.0 co-simulation FMUs",
    args_conflicts_with_subcommands = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Cmd>,
    #[command(flatten)]
    fuzz: FuzzArgs,
}

#[derive(Args)]
struct FuzzArgs {
    /// An FMU to fuzz (repeatable).
    #[arg(long = "fmu")]
    fmus: Vec<PathBuf>,
    /// Sequences per FMU.
    #[arg(long, default_value_t = 1000)]
    sequences: u64,
    /// Seed of the first sequence (sequence k uses seed + k).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Longest sequence (calls, not counting the clean-up at its end).
    #[arg(long, default_value_t = 40)]
    max_len: usize,
    /// Seconds one sequence may run before it counts as hung.
    #[arg(long, default_value_t = 60.0)]
    timeout: f64,
    /// Child processes at once (default: the number of cores).
    #[arg(long)]
    jobs: Option<usize>,
    /// Sequences per child process.
    #[arg(long, default_value_t = 2000)]
    batch: u64,
    /// `name=value` set right after most instantiations when the FMU has that variable
    /// (repeatable), e.g. to make an expensive initialization cheap.
    #[arg(long = "preset", value_parser = parse_preset)]
    presets: Vec<(String, String)>,
    /// Percentage of instances that get the presets.
    #[arg(long, default_value_t = 90)]
    preset_percent: u32,
    /// Address-space limit of each child process in MiB (0: none).
    #[arg(long, default_value_t = 4096)]
    mem_limit_mb: u64,
    /// Failure reports printed in full.
    #[arg(long, default_value_t = 3)]
    show: usize,
    /// Stop after this many failing sequences (0: run them all).
    #[arg(long, default_value_t = 0)]
    max_failures: usize,
    /// Run in this process, printing every call to stderr before it is made (for replaying
    /// one seed; no crash isolation).
    #[arg(long)]
    trace: bool,
}

#[derive(Subcommand)]
enum Cmd {
    /// Instantiate/initialize/step/FMU-state/free cycles (run this under valgrind).
    Cycles {
        #[arg(long = "fmu")]
        fmus: Vec<PathBuf>,
        #[arg(long, default_value_t = 1000)]
        cycles: u64,
        /// Communication steps per cycle.
        #[arg(long, default_value_t = 10)]
        steps: u64,
        #[arg(long, default_value_t = 1e-3)]
        step_size: f64,
        #[arg(long = "preset", value_parser = parse_preset)]
        presets: Vec<(String, String)>,
    },
    /// Runs sequences in this process and prints the child protocol (used by the runner).
    #[command(hide = true)]
    Worker {
        #[arg(long)]
        fmu: PathBuf,
        #[arg(long)]
        first: u64,
        #[arg(long)]
        count: u64,
        #[arg(long, default_value_t = 40)]
        max_len: usize,
        #[arg(long = "preset", value_parser = parse_preset)]
        presets: Vec<(String, String)>,
        #[arg(long, default_value_t = 90)]
        preset_percent: u32,
        #[arg(long)]
        trace: bool,
    },
}

fn parse_preset(s: &str) -> Result<(String, String), String> {
    s.split_once('=')
        .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        .ok_or_else(|| format!("expected name=value, got {s:?}"))
}

fn main() -> ExitCode {
    match real_main() {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => {
            eprintln!("fmi-fuzz: {e:#}");
            ExitCode::from(2)
        }
    }
}

fn real_main() -> Result<bool> {
    let cli = Cli::parse();
    match cli.command {
        Some(Cmd::Worker {
            fmu,
            first,
            count,
            max_len,
            presets,
            preset_percent,
            trace,
        }) => {
            let cfg = Config {
                max_len,
                trace: if trace { Trace::Stream } else { Trace::Collect },
                presets,
                preset_percent,
            };
            runner::worker(&fmu, &cfg, first, count)?;
            Ok(true)
        }
        Some(Cmd::Cycles {
            fmus,
            cycles,
            steps,
            step_size,
            presets,
        }) => {
            if fmus.is_empty() {
                bail!("give at least one --fmu");
            }
            for fmu in &fmus {
                let start = std::time::Instant::now();
                let r = fmi_fuzz::cycles::run(fmu, cycles, steps, step_size, &presets)?;
                println!(
                    "{}: {} cycles, {} FMI calls, {} steps, {} FMU states: all statuses as expected, outputs identical in every cycle ({:.1} s)",
                    fmu.display(),
                    r.cycles,
                    r.calls,
                    r.steps,
                    r.states,
                    start.elapsed().as_secs_f64()
                );
            }
            Ok(true)
        }
        None => fuzz(cli.fuzz),
    }
}

fn fuzz(a: FuzzArgs) -> Result<bool> {
    if a.fmus.is_empty() {
        bail!("give at least one --fmu (or a subcommand; see --help)");
    }
    let jobs = a
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let mut all_ok = true;
    for fmu in &a.fmus {
        let o = RunOptions {
            fmu: fmu.clone(),
            sequences: a.sequences,
            seed: a.seed,
            max_len: a.max_len,
            timeout: Duration::from_secs_f64(a.timeout),
            jobs,
            batch: a.batch.max(1),
            presets: a.presets.clone(),
            preset_percent: a.preset_percent,
            mem_limit_mb: a.mem_limit_mb,
            show: a.show,
            max_failures: a.max_failures,
        };
        let report = if a.trace {
            runner::run_in_process(&o, Trace::Stream)?
        } else {
            let mut last = std::time::Instant::now();
            runner::run(&o, |done, total| {
                if last.elapsed() > Duration::from_secs(10) {
                    eprintln!("  {}: {done}/{total} sequences", fmu.display());
                    last = std::time::Instant::now();
                }
            })?
        };
        println!(
            "{}: {} sequences (seeds {}..={}), {} FMI calls, {:.1} s, {} failing sequence(s)",
            fmu.display(),
            report.sequences,
            a.seed,
            a.seed.wrapping_add(a.sequences.saturating_sub(1)),
            report.calls,
            report.seconds,
            report.failures.len()
        );
        if report.stopped_early {
            println!(
                "stopped after {} failing sequence(s) (--max-failures)",
                report.failures.len()
            );
        }
        print!("{}", report.render_stats());
        if !report.failures.is_empty() {
            all_ok = false;
            let seeds: Vec<String> = report
                .failures
                .iter()
                .take(50)
                .map(|f| f.0.to_string())
                .collect();
            println!(
                "FAILED: seeds {}{}",
                seeds.join(", "),
                if report.failures.len() > 50 {
                    ", ..."
                } else {
                    ""
                }
            );
            // The kinds of failure (first failure of each sequence, digits masked).
            let mut kinds: std::collections::BTreeMap<String, (usize, u64)> = Default::default();
            for (seed, text) in &report.failures {
                let first = text.lines().next().unwrap_or("");
                let key: String = first
                    .chars()
                    .map(|c| if c.is_ascii_digit() { '#' } else { c })
                    .take(140)
                    .collect();
                let e = kinds.entry(key).or_insert((0, *seed));
                e.0 += 1;
            }
            let mut kinds: Vec<_> = kinds.into_iter().collect();
            kinds.sort_by_key(|k| std::cmp::Reverse(k.1.0));
            println!("failure kinds (count, first seed):");
            for (k, (n, seed)) in kinds.iter().take(20) {
                println!("  {n:>6}  seed {seed:<8} {k}");
            }
            for (seed, text) in report.failures.iter().take(a.show) {
                println!("--- seed {seed} ---");
                // The trace can be long: its first failure lines and the calls.
                let lines: Vec<&str> = text.lines().collect();
                for l in lines.iter().take(200) {
                    println!("{l}");
                }
                if lines.len() > 200 {
                    println!("... ({} more lines)", lines.len() - 200);
                }
                println!(
                    "replay: fmi-fuzz --fmu {} --seed {seed} --sequences 1 --max-len {} --trace{}",
                    fmu.display(),
                    a.max_len,
                    a.presets
                        .iter()
                        .map(|(k, v)| format!(" --preset {k}={v}"))
                        .collect::<String>()
                        + &format!(" --preset-percent {}", a.preset_percent)
                );
            }
        }
    }
    Ok(all_ok)
}
