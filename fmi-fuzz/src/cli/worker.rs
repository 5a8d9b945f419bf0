//! `fmi-fuzz worker` (hidden): the child process of the runner, which re-invokes this binary
//! so that a crash or a hang is caught with the seed that causes it.

use super::parse_preset;
use crate::fuzz::{Config, Trace};
use crate::runner;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

/// The options the runner passes to its child processes (not meant to be typed).
#[derive(Args)]
pub struct WorkerArgs {
    /// The FMU to fuzz.
    #[arg(long)]
    pub fmu: PathBuf,
    /// Seed of the first sequence of this batch.
    #[arg(long)]
    pub first: u64,
    /// Sequences in this batch.
    #[arg(long)]
    pub count: u64,
    /// Longest sequence, in calls.
    #[arg(long, default_value_t = 40)]
    pub max_len: usize,
    /// `name=value` set after most instantiations (repeatable).
    #[arg(long = "preset", value_parser = parse_preset)]
    pub presets: Vec<(String, String)>,
    /// Percentage of instances that get the presets.
    #[arg(long, default_value_t = 90)]
    pub preset_percent: u32,
    /// Print every call to stderr before making it.
    #[arg(long)]
    pub trace: bool,
}

/// Runs the sequences, printing the runner's protocol on stdout.
pub fn worker(a: WorkerArgs) -> Result<bool> {
    let cfg = Config {
        max_len: a.max_len,
        trace: if a.trace {
            Trace::Stream
        } else {
            Trace::Collect
        },
        presets: a.presets,
        preset_percent: a.preset_percent,
    };
    runner::worker(&a.fmu, &cfg, a.first, a.count)?;
    Ok(true)
}
