//! `orchestrator export-ssp`: a system written as an .ssp archive with its FMUs.

use super::fmu_sources;
use crate::master::RunError;
use clap::Args;
use std::path::PathBuf;

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
}

pub fn export_ssp(args: &ExportArgs) -> Result<(), RunError> {
    let loaded = crate::ssp::read_with(&args.system, &fmu_sources(&args.fmus)?)
        .map_err(|e| RunError::Config(e.to_string()))?;
    crate::ssp::write_ssp(&loaded.system, &args.out).map_err(|e| RunError::Config(e.to_string()))
}
