//! `fmi-fuzz --fmu X.fmu ...` (the default command): runs the sequences through the
//! [`runner`] (child processes, or this process with `--trace`) and prints one summary per FMU,
//! and for failures their seeds, their kinds and the first reports with a replay command.

use super::parse_preset;
use crate::fuzz::Trace;
use crate::runner::{self, Report, RunOptions};
use anyhow::{Result, bail};
use clap::Args;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// The options of the default command.
#[derive(Args)]
pub struct FuzzArgs {
    /// An FMU to fuzz (repeatable).
    #[arg(long = "fmu")]
    pub fmus: Vec<PathBuf>,
    /// Sequences per FMU.
    #[arg(long, default_value_t = 1000)]
    pub sequences: u64,
    /// Seed of the first sequence (sequence k uses seed + k).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Longest sequence (calls, not counting the clean-up at its end).
    #[arg(long, default_value_t = 40)]
    pub max_len: usize,
    /// Seconds one sequence may run before it counts as hung.
    #[arg(long, default_value_t = 60.0)]
    pub timeout: f64,
    /// Child processes at once (default: the number of cores).
    #[arg(long)]
    pub jobs: Option<usize>,
    /// Sequences per child process.
    #[arg(long, default_value_t = 2000)]
    pub batch: u64,
    /// `name=value` set right after most instantiations when the FMU has that variable
    /// (repeatable), e.g. to make an expensive initialization cheap.
    #[arg(long = "preset", value_parser = parse_preset)]
    pub presets: Vec<(String, String)>,
    /// Percentage of instances that get the presets.
    #[arg(long, default_value_t = 90)]
    pub preset_percent: u32,
    /// Address-space limit of each child process in MiB (0: none).
    #[arg(long, default_value_t = 4096)]
    pub mem_limit_mb: u64,
    /// Failure reports printed in full.
    #[arg(long, default_value_t = 3)]
    pub show: usize,
    /// Stop after this many failing sequences (0: run them all).
    #[arg(long, default_value_t = 0)]
    pub max_failures: usize,
    /// Run in this process, printing every call to stderr before it is made (for replaying
    /// one seed; no crash isolation).
    #[arg(long)]
    pub trace: bool,
}

/// Fuzzes every FMU; returns whether no sequence failed.
pub fn fuzz(a: FuzzArgs) -> Result<bool> {
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
            let mut last = Instant::now();
            runner::run(&o, |done, total| {
                if last.elapsed() > Duration::from_secs(10) {
                    eprintln!("  {}: {done}/{total} sequences", fmu.display());
                    last = Instant::now();
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
            print_failures(&report, fmu, &a);
        }
    }
    Ok(all_ok)
}

/// The failing seeds, the kinds of failure, and the first `--show` reports with a command
/// that replays each.
fn print_failures(report: &Report, fmu: &Path, a: &FuzzArgs) {
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
    println!("failure kinds (count, first seed):");
    for (k, n, seed) in failure_kinds(&report.failures).iter().take(20) {
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

/// The kinds of failure: each sequence's first failure line with its digits masked (cut at
/// 140 characters), with how many sequences have it and the first seed that does; the most
/// frequent first (ties in the order of the masked text).
fn failure_kinds(failures: &[(u64, String)]) -> Vec<(String, usize, u64)> {
    let mut kinds: BTreeMap<String, (usize, u64)> = BTreeMap::new();
    for (seed, text) in failures {
        let first = text.lines().next().unwrap_or("");
        let key: String = first
            .chars()
            .map(|c| if c.is_ascii_digit() { '#' } else { c })
            .take(140)
            .collect();
        kinds.entry(key).or_insert((0, *seed)).0 += 1;
    }
    let mut kinds: Vec<_> = kinds.into_iter().map(|(k, (n, s))| (k, n, s)).collect();
    kinds.sort_by_key(|k| std::cmp::Reverse(k.1));
    kinds
}

#[cfg(test)]
mod tests {
    use super::failure_kinds;

    #[test]
    fn failure_kinds_mask_digits_and_count() {
        let failures = [
            (7, "status 3 from fmi2DoStep\ntrace".to_string()),
            (9, "crash: signal 11".to_string()),
            (12, "status 1 from fmi2DoStep".to_string()),
            (20, String::new()),
        ];
        assert_eq!(
            failure_kinds(&failures),
            [
                ("status # from fmi#DoStep".to_string(), 2, 7),
                (String::new(), 1, 20),
                ("crash: signal ##".to_string(), 1, 9),
            ]
        );
        let long = [(1, "x".repeat(300))];
        assert_eq!(failure_kinds(&long)[0].0.len(), 140);
    }
}
