//! The standard case run once through the master, as `orchestrator run studies/standard.ssd`
//! runs it, with its accuracy (`alignment-studies run`): `metrics.json` beside `results.csv`,
//! evaluated from the recorded table in memory, and the table beside the paper's on screen.

use super::Report;
use crate::Error;
use crate::study::{standard, standard_case};
use orchestrator::cli::run::{Settings, run_system};
use orchestrator::master::RunSummary;
use orchestrator::outdir::OutputDir;
use std::path::Path;

/// A finished run of the standard case and its report.
pub struct StandardRun {
    /// What the master's run did (steps, rows, results file).
    pub summary: RunSummary,
    /// `metrics.json` and the tables, when results were written and could be evaluated; in the
    /// note, why there are none (or none for the lagged output).
    pub report: Report,
    /// The output directory, locked until this is dropped (after the report is written).
    _out: Option<OutputDir>,
}

/// Runs the standard case with the FMUs `vehicle` and `estimator` and the command line's
/// `settings`, and evaluates it when the results were recorded.
pub fn run(vehicle: &Path, estimator: &Path, settings: &Settings) -> Result<StandardRun, Error> {
    let system = standard_case::system(vehicle, estimator)?;
    let program = concat!("alignment-studies ", env!("CARGO_PKG_VERSION"));
    let finished = run_system(&system, settings, program, &["metrics.json"], true)?;
    let report = match (&finished.summary.results, &finished.summary.table) {
        (Some(results), Some(table)) => evaluate(table, &results.with_file_name("metrics.json")),
        _ => Report::default(),
    };
    Ok(StandardRun {
        summary: finished.summary,
        report,
        _out: finished.out,
    })
}

/// The accuracy of a standard-case table, as the report of `metrics.json` at `path`.
fn evaluate(table: &orchestrator::master::Table, path: &Path) -> Report {
    let mut report = Report::default();
    let m = match standard::evaluate_results(table) {
        Ok(m) => m,
        Err(e) => {
            report.note = format!("no accuracy metrics: {e}");
            return report;
        }
    };
    let lagged = match standard::evaluate_lagged(table) {
        Some(Ok(l)) => Some(l),
        Some(Err(e)) => {
            report.note = format!("no accuracy metrics for the lagged output: {e}");
            None
        }
        None => None,
    };
    report.markdown = format!(
        "Alignment estimate against the truth (EN 13848 bands, this run's track only; {}):\n{}",
        path.display(),
        standard::table(&m)
    );
    if let Some(l) = &lagged {
        report
            .markdown
            .push_str("Fixed-lag output alignment_lagged at distance_lagged:\n");
        report.markdown.push_str(&standard::table(l));
    }
    report.file(
        path.to_path_buf(),
        standard::metrics_json(&m, lagged.as_ref()),
    );
    report
}
