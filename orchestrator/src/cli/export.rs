//! `orchestrator export-ssp`: a system written as an .ssp archive with its FMUs.

use super::fmu_sources;
use crate::master::RunError;
use clap::Args;
use std::path::{Path, PathBuf};

/// `export-ssp`'s options.
#[derive(Args, Debug)]
pub struct ExportArgs {
    /// The .ssp file to write.
    pub out: PathBuf,
    /// The SSP system (.ssd or .ssp) to export, e.g. studies/standard.ssd.
    #[arg(long, required = true)]
    pub system: PathBuf,
    /// Export a component with this FMU instead of the system's source: COMPONENT=PATH
    /// (repeatable).
    #[arg(long = "fmu", value_name = "COMPONENT=PATH")]
    pub fmus: Vec<String>,
    /// Replace an existing file at the output path (never the system, an FMU, a symlink, a FIFO
    /// or a directory).
    #[arg(long)]
    pub force: bool,
}

/// Checks the output path by the single-file rule ([`crate::outfile`]) before and after
/// reading the system (then its FMUs are known as inputs), then writes the archive through a
/// temporary file.
pub fn export_ssp(args: &ExportArgs) -> Result<(), RunError> {
    let replace = crate::outfile::Replace {
        force: args.force,
        mark: None,
    };
    let refused = |e: std::io::Error| RunError::Io(e.to_string());
    crate::outfile::check(&args.out, &[&args.system], replace).map_err(refused)?;
    let loaded = crate::ssp::read_with(&args.system, &fmu_sources(&args.fmus)?)
        .map_err(|e| RunError::Config(e.to_string()))?;
    let mut inputs: Vec<&Path> = vec![&args.system];
    inputs.extend(loaded.system.components.iter().map(|c| c.source.as_path()));
    crate::outfile::check(&args.out, &inputs, replace).map_err(refused)?;
    crate::ssp::write_ssp(&loaded.system, &args.out).map_err(|e| RunError::Config(e.to_string()))
}
