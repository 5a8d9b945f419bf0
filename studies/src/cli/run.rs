//! `alignment-studies run`: the standard case (`standard.ssd`) through the master with its
//! accuracy, `metrics.json` ([`crate::report::standard`]).

use super::StandardFmus;
use crate::Error;
use crate::report::standard::StandardRun;
use clap::Args;
use orchestrator::cli::run::Settings;

/// `run`'s options.
#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    /// The vehicle and estimator FMUs.
    #[command(flatten)]
    pub fmus: StandardFmus,
    /// The master's run settings, as `orchestrator run` takes them.
    #[command(flatten)]
    pub settings: Settings,
}

/// Runs and evaluates the standard case.
pub fn execute(a: &RunArgs) -> Result<StandardRun, Error> {
    crate::report::standard::run(&a.fmus.vehicle, &a.fmus.estimator, &a.settings)
}
