//! `alignment-studies stage`: fits a tap bank's long-wave stage
//! ([`crate::study::learned::stage`]) and writes the bank with it.

use super::{Report, StandardFmus};
use crate::Error;
use crate::study::learned::stage::{StageOptions, fit};
use clap::Args;
use fmu_estimator::learned::bank::Bank;
use std::path::PathBuf;

/// `stage`'s options.
#[derive(Args, Clone, Debug)]
pub struct StageArgs {
    /// The vehicle and estimator FMUs.
    #[command(flatten)]
    pub fmus: StandardFmus,
    /// The tap bank whose causal output the stage corrects (a stage it has is fitted anew).
    #[arg(long, value_name = "BANK")]
    pub bank: PathBuf,
    /// Track seeds of the training runs (their runs share the training distance).
    #[arg(long, value_delimiter = ',', default_value = "101,107,108,109,110")]
    pub seeds: Vec<u32>,
    /// Track seeds the ridge is chosen on (neither the training seed nor an evaluation seed).
    #[arg(long, value_delimiter = ',', default_value = "102,103")]
    pub validation_seeds: Vec<u32>,
    /// The bank to write: --bank with the stage (a file this command or `taps` wrote is
    /// replaced; never --bank itself).
    #[arg(long)]
    pub out: PathBuf,
    /// Replace an existing file at --out that no fit wrote (never an input, a symlink, a FIFO
    /// or a directory).
    #[arg(long)]
    pub force: bool,
}

/// How every tap bank begins (`fmu-estimator/src/learned/bank.rs`).
const MARK: &[u8] = b"learned-taps ";

/// Checks the options and the files, fits the stage, and reports each speed's ridge and
/// validation figures.
pub fn execute(a: &StageArgs, log: &dyn Fn(&str)) -> Result<Report, Error> {
    let inputs = [
        a.fmus.vehicle.as_path(),
        a.fmus.estimator.as_path(),
        a.bank.as_path(),
    ];
    let guard = super::guard(&a.out, &inputs, a.force, Some(MARK))?;
    if a.seeds.is_empty() || a.validation_seeds.is_empty() {
        return Err(Error::input(
            "--seeds and --validation-seeds: at least one each",
        ));
    }
    if let Some(s) = a.validation_seeds.iter().find(|s| a.seeds.contains(*s)) {
        return Err(Error::input(format!(
            "track seed {s} is in --seeds and --validation-seeds: training and validation seeds are disjoint"
        )));
    }
    if let Some(s) = a
        .seeds
        .iter()
        .chain(&a.validation_seeds)
        .find(|s| (1..=5).contains(*s))
    {
        return Err(Error::input(format!(
            "track seed {s} is an evaluation seed (1-5): never fitted or chosen on"
        )));
    }
    let bank = Bank::load(&a.bank).map_err(|e| Error::input(format!("--bank: {e}")))?;
    let o = StageOptions {
        training_seeds: a.seeds.clone(),
        validation_seeds: a.validation_seeds.clone(),
        speeds: vec![],
    };
    let started = std::time::Instant::now();
    let staged = fit(&a.fmus.fmus(), &o, &bank, log)?;
    let lines: Vec<String> = staged
        .stage
        .iter()
        .flat_map(|s| &s.entries)
        .map(|e| {
            format!(
                "{:>5} m/s {:<52} ridge {:.0e}: validation objective (sum of Jrel^2 over whole, D1, D2, D3) {:.4} without the stage, {:.4} with it",
                e.speed,
                e.channels.join(","),
                e.ridge,
                e.validation[0],
                e.validation[1]
            )
        })
        .collect();
    let mut report = Report {
        markdown: lines.join("\n"),
        note: format!(
            "long-wave stage in {:.1} s; wrote {}",
            started.elapsed().as_secs_f64(),
            a.out.display()
        ),
        ..Report::default()
    };
    report.file(a.out.clone(), staged.to_bytes());
    report.guarded.push(guard);
    Ok(report)
}
