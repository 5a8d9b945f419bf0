//! `alignment-studies smooth`: the estimator's filter and RTS smoother (and optionally a learned
//! estimator) over recorded sensor signals.

use super::Report;
use crate::Error;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Clone, Debug)]
pub struct SmoothArgs {
    /// The recorded signals: CSV, or Parquet by the .parquet extension.
    pub input: PathBuf,
    /// The table to write (time, distance, alignment_filtered\[_std\], alignment_smoothed\[_std\]):
    /// Parquet if it ends in .parquet, else CSV.
    #[arg(long, default_value = "out/smoothed.csv")]
    pub out: PathBuf,
    /// Set an estimator parameter: name=value (repeatable), e.g. alignment_model=3.
    #[arg(long = "set", value_name = "PARAMETER=VALUE")]
    pub set: Vec<String>,
    /// A calibration file instead of the one built into the estimator.
    #[arg(long)]
    pub calibration: Option<PathBuf>,
    /// A learned smoother (from `learn`): adds the columns alignment_learned and
    /// alignment_hybrid.
    #[arg(long)]
    pub learned: Option<PathBuf>,
}

/// Filters and smooths the record into `out` ([`crate::smooth::smooth_file`]); the report's
/// note says what was done.
pub fn execute(a: &SmoothArgs) -> Result<Report, Error> {
    let overrides = a
        .set
        .iter()
        .map(|s| {
            orchestrator::cli::split_assignment(s)
                .map(|(k, v)| (k.trim().to_string(), v.trim().to_string()))
        })
        .collect::<Result<Vec<_>, _>>()?;
    crate::report::create_parent(&a.out)?;
    let processed = crate::smooth::smooth_file(
        &a.input,
        &a.out,
        &overrides,
        a.calibration.as_deref(),
        a.learned.as_deref(),
    )?;
    Ok(Report {
        note: format!(
            "{} samples filtered and smoothed ({} updates skipped); wrote {}",
            processed.filtered.len(),
            processed.skipped,
            a.out.display()
        ),
        ..Report::default()
    })
}
