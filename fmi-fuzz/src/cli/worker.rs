//! `fmi-fuzz worker` (hidden): the child process of the runner, which re-invokes this binary
//! so that a crash or a hang is caught with the seed that causes it.

use super::parse_preset;
use crate::fuzz::{Config, Trace};
use crate::runner;
use anyhow::Result;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct WorkerArgs {
    #[arg(long)]
    pub fmu: PathBuf,
    #[arg(long)]
    pub first: u64,
    #[arg(long)]
    pub count: u64,
    #[arg(long, default_value_t = 40)]
    pub max_len: usize,
    #[arg(long = "preset", value_parser = parse_preset)]
    pub presets: Vec<(String, String)>,
    #[arg(long, default_value_t = 90)]
    pub preset_percent: u32,
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
