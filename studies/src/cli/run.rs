//! `alignment-studies run`: the standard case (`standard.ssd`) through the master, as
//! `orchestrator run studies/standard.ssd` runs it, and its accuracy from the recorded table in
//! memory: `metrics.json` beside `results.csv` (listed in the manifest), the table on stdout.

use super::StandardFmus;
use crate::Error;
use crate::study::{standard, standard_case};
use clap::Args;
use orchestrator::cli::run::{Finished, Settings, run_system};
use std::path::PathBuf;

#[derive(Args, Clone, Debug)]
pub struct RunArgs {
    #[command(flatten)]
    pub fmus: StandardFmus,
    #[command(flatten)]
    pub settings: Settings,
}

/// A finished run of the standard case and its accuracy.
pub struct StandardRun {
    /// The run, its output directory still locked until metrics.json is written.
    pub run: Finished,
    /// `metrics.json`'s path and text, and the tables to print, when results were written and
    /// could be evaluated.
    pub metrics: Option<(PathBuf, String, String)>,
    /// Why there are no metrics (or none for the lagged output).
    pub notes: Vec<String>,
}

pub fn run(a: &RunArgs) -> Result<StandardRun, Error> {
    let system = standard_case::system(&a.fmus.vehicle, &a.fmus.estimator)?;
    let program = concat!("alignment-studies ", env!("CARGO_PKG_VERSION"));
    let run = run_system(&system, &a.settings, program, &["metrics.json"], true)?;
    let mut notes = vec![];
    let (Some(results), Some(table)) = (&run.summary.results, &run.summary.table) else {
        return Ok(StandardRun {
            run,
            metrics: None,
            notes,
        });
    };
    let m = match standard::evaluate_results(table) {
        Ok(m) => m,
        Err(e) => {
            notes.push(format!("no accuracy metrics: {e}"));
            return Ok(StandardRun {
                run,
                metrics: None,
                notes,
            });
        }
    };
    let lagged = match standard::evaluate_lagged(table) {
        Some(Ok(l)) => Some(l),
        Some(Err(e)) => {
            notes.push(format!("no accuracy metrics for the lagged output: {e}"));
            None
        }
        None => None,
    };
    let path = results.with_file_name("metrics.json");
    let mut text = format!(
        "Alignment estimate against the truth (EN 13848 bands, this run's track only; {}):\n{}",
        path.display(),
        standard::table(&m)
    );
    if let Some(l) = &lagged {
        text.push_str("Fixed-lag output alignment_lagged at distance_lagged:\n");
        text.push_str(&standard::table(l));
    }
    let json = standard::metrics_json(&m, lagged.as_ref());
    Ok(StandardRun {
        run,
        metrics: Some((path, json, text)),
        notes,
    })
}
