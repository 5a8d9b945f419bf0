//! `alignment-studies smooth`: the estimator's filter and RTS smoother (and optionally a learned
//! estimator) over recorded sensor signals.

use super::Report;
use crate::Error;
use clap::Args;
use std::path::PathBuf;

/// `smooth`'s options.
#[derive(Args, Clone, Debug)]
pub struct SmoothArgs {
    /// The recorded signals: CSV, or Parquet by the .parquet extension.
    pub input: PathBuf,
    /// The table to write (time, distance, alignment_filtered and alignment_smoothed, each
    /// with its _std): Parquet if it ends in .parquet, else CSV. An existing file is replaced
    /// only if it is an earlier smooth CSV output, or with --force; never the input.
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
    /// The line's design is not known: fit it from the recording's sensors (needs
    /// ws_roll_rate; not with design columns or line_file) and remove its response, as
    /// track_alignment.fit_design does (docs/accuracy.md, "Curves").
    #[arg(long)]
    pub fit_design: bool,
    /// With --fit-design, also write the fitted design as a line file (distance,curvature,cant),
    /// which the estimator FMU takes as line_file on later runs over the same line. An
    /// existing file is replaced only if this command wrote it, or with --force.
    #[arg(long, value_name = "LINE.csv", requires = "fit_design")]
    pub design_out: Option<PathBuf>,
    /// Replace an existing file at --out that this command did not write (never the input, a
    /// symlink, a FIFO or a directory).
    #[arg(long)]
    pub force: bool,
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
    let mut inputs = vec![a.input.as_path()];
    inputs.extend(a.calibration.as_deref());
    inputs.extend(a.learned.as_deref());
    // Checked before the recording is read, and again at the rename.
    let mark = (!orchestrator::parquet::is_parquet(&a.out)).then_some(crate::smooth::CSV_MARK);
    let guard = super::guard(&a.out, &inputs, a.force, mark)?;
    let line_guard = match &a.design_out {
        Some(path) => {
            let mut with_out = inputs.clone();
            with_out.push(a.out.as_path());
            Some(super::guard(
                path,
                &with_out,
                a.force,
                Some(crate::smooth::LINE_MARK),
            )?)
        }
        None => None,
    };
    let fit_design = a.fit_design.then(|| crate::smooth::FitDesign {
        line_out: line_guard.as_ref().map(|g| (g.path.as_path(), g.replace)),
    });
    let processed = crate::smooth::smooth_file(
        &a.input,
        &a.out,
        &overrides,
        a.calibration.as_deref(),
        a.learned.as_deref(),
        fit_design,
        guard.replace,
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
