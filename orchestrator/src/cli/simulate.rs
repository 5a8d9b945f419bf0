//! `orchestrator simulate FMU`: one FMU, optionally driven by input signals from a CSV file.

use super::{Common, progress_bar, split_assignment};
use crate::master::{RunError, RunSummary};
use crate::system::Endpoint;
use clap::Args;
use std::path::PathBuf;

/// `simulate`'s options.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// The .fmu file.
    pub fmu: PathBuf,
    /// Input signals: CSV, or Parquet by the .parquet extension, with a `time` column and one
    /// column per input variable (Real continuous inputs interpolated; discrete, Integer,
    /// Enumeration and Boolean ones held); a recording's `distance` column is ignored.
    #[arg(long)]
    pub input: Option<PathBuf>,
    /// Replay a recorded results.csv exactly: the value set at t is the row of t + h (a
    /// recorded row t + h holds what the consumer read for the step from t). Without it the
    /// inputs are the rows at t, one step later than in the recorded run.
    #[arg(long, requires = "input")]
    pub replay: bool,
    /// The options every run shares.
    #[command(flatten)]
    pub common: Common,
    /// Set a parameter before initialization: variable=value (repeatable).
    #[arg(long = "set", value_name = "VARIABLE=VALUE")]
    pub set: Vec<String>,
}

/// Runs the FMU; stop and step default to the input's last time and the FMU's default
/// experiment.
pub fn simulate(args: &SimulateArgs) -> Result<RunSummary, RunError> {
    let signals = match &args.input {
        Some(p) => Some(crate::simulate::Signals::read(p).map_err(RunError::Config)?),
        None => None,
    };
    let settings: Vec<(String, String)> = args
        .set
        .iter()
        .map(|s| split_assignment(s).map(|(a, b)| (a.to_string(), b.to_string())))
        .collect::<Result<_, _>>()?;
    let fmu = fmi_import::Fmu::open(&args.fmu)?;
    let de = fmu
        .model_description()
        .default_experiment
        .clone()
        .unwrap_or_default();
    drop(fmu);
    let c = &args.common;
    let stop = c
        .stop
        .or(signals.as_ref().and_then(|s| s.time.last().copied()))
        .or(de.stop_time);
    let step = c.step.or(de.step_size);
    let (Some(stop), Some(step)) = (stop, step) else {
        return Err(RunError::Config(
            "give --stop and --step (the FMU has no default experiment for them)".into(),
        ));
    };
    let record = if c.record.is_empty() {
        None
    } else {
        let name = args
            .fmu
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("fmu")
            .to_string();
        Some(c.record.iter().map(|r| Endpoint::new(&name, r)).collect())
    };
    let mut opts = c.run_options(c.start.unwrap_or(0.0), stop, step, record)?;
    let _out = c.hold_output(
        &mut opts,
        concat!("orchestrator ", env!("CARGO_PKG_VERSION")),
        &[],
        &[("fmu", args.fmu.as_path())],
        &args.set,
    )?;
    crate::simulate::simulate(
        &args.fmu,
        signals.as_ref(),
        &settings,
        &opts,
        args.replay,
        &mut progress_bar(),
        &c.interrupt,
    )
}
