//! `fmi-fuzz cycles`: the memory cycles of [`crate::cycles`], one summary line per FMU.

use super::parse_preset;
use anyhow::{Result, bail};
use clap::Args;
use std::path::PathBuf;

/// The options of `fmi-fuzz cycles`.
#[derive(Args)]
pub struct CyclesArgs {
    /// An FMU to run the cycles on (repeatable).
    #[arg(long = "fmu")]
    pub fmus: Vec<PathBuf>,
    /// Cycles per FMU: instantiate, initialize, step, FMU states, free.
    #[arg(long, default_value_t = 1000)]
    pub cycles: u64,
    /// Communication steps per cycle.
    #[arg(long, default_value_t = 10)]
    pub steps: u64,
    /// Communication step size in seconds.
    #[arg(long, default_value_t = 1e-3)]
    pub step_size: f64,
    /// `name=value` set after each instantiation (repeatable), e.g. to make an expensive
    /// initialization cheap.
    #[arg(long = "preset", value_parser = parse_preset)]
    pub presets: Vec<(String, String)>,
}

/// Runs the cycles on every FMU; an unexpected status or output is an error.
pub fn cycles(a: CyclesArgs) -> Result<bool> {
    if a.fmus.is_empty() {
        bail!("give at least one --fmu");
    }
    for fmu in &a.fmus {
        let start = std::time::Instant::now();
        let r = crate::cycles::run(fmu, a.cycles, a.steps, a.step_size, &a.presets)?;
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
