//! `orchestrator info FMU`: the description of an FMU, as text.

use crate::master::RunError;
use clap::Args;
use std::path::PathBuf;

#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The .fmu file.
    pub fmu: PathBuf,
}

pub fn info(args: &InfoArgs) -> Result<String, RunError> {
    let archive = crate::info::read_archive(&args.fmu).map_err(RunError::Config)?;
    Ok(crate::info::describe(&args.fmu, &archive))
}
