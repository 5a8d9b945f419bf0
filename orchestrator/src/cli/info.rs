//! `orchestrator info FMU`: the description of an FMU, as text.

use crate::master::RunError;
use clap::Args;
use std::path::PathBuf;

/// `info`'s options.
#[derive(Args, Debug)]
pub struct InfoArgs {
    /// The .fmu file.
    pub fmu: PathBuf,
}

/// The FMU's description as `info` prints it; an unreadable archive or model description is
/// [`RunError::Config`] (exit 2). Nothing is extracted or loaded.
pub fn info(args: &InfoArgs) -> Result<String, RunError> {
    let archive = crate::info::read_archive(&args.fmu).map_err(RunError::Config)?;
    Ok(crate::info::describe(&args.fmu, &archive))
}
