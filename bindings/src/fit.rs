//! `fit`: `alignment-studies fit` from Python. The keyword arguments become the command's
//! options and are parsed by the command's own parser, so every check, default and message is
//! the command line's; the fit runs with the GIL released and returns the report.

use alignment_studies::cli::fit::{FitArgs, execute};
use clap::{Args, FromArgMatches};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::ffi::OsString;
use std::path::PathBuf;

/// A list option: `--name a,b,c`.
fn list(argv: &mut Vec<OsString>, name: &str, values: Option<Vec<f64>>) {
    if let Some(v) = values {
        argv.push(format!("--{name}").into());
        argv.push(
            v.iter()
                .map(|x| x.to_string())
                .collect::<Vec<_>>()
                .join(",")
                .into(),
        );
    }
}

/// Fits the estimator to a vehicle FMU (default) or to `recordings` against `reference`, into
/// the new directory `out`, and returns its report (Markdown). `vehicle_settings` are the
/// vehicle FMU's parameters (`--set vehicle.NAME=VALUE`).
#[pyfunction]
#[pyo3(signature = (
    out, *, vehicle=None, estimator=None, vehicle_settings=None, recordings=None, reference=None,
    speeds=None, kalker_scales=None, conicities=None, lags=None, roll_rate=true, seed=None,
    validation_seeds=None, evaluation_seeds=None, validation_share=None, calibration=None
))]
#[allow(clippy::too_many_arguments)]
pub fn fit(
    py: Python<'_>,
    out: PathBuf,
    vehicle: Option<PathBuf>,
    estimator: Option<PathBuf>,
    vehicle_settings: Option<&Bound<'_, PyDict>>,
    recordings: Option<Vec<PathBuf>>,
    reference: Option<PathBuf>,
    speeds: Option<Vec<f64>>,
    kalker_scales: Option<Vec<f64>>,
    conicities: Option<Vec<f64>>,
    lags: Option<Vec<f64>>,
    roll_rate: bool,
    seed: Option<u32>,
    validation_seeds: Option<Vec<u32>>,
    evaluation_seeds: Option<Vec<u32>>,
    validation_share: Option<f64>,
    calibration: Option<PathBuf>,
) -> PyResult<String> {
    // `--name=value`: a path that starts with '-' stays a value.
    let with = |name: &str, p: PathBuf| -> OsString {
        let mut a = OsString::from(format!("--{name}="));
        a.push(p.as_os_str());
        a
    };
    let mut argv: Vec<OsString> = vec!["fit".into(), "--quiet".into(), with("out", out)];
    let mut path = |name: &str, p: Option<PathBuf>| {
        if let Some(p) = p {
            argv.push(with(name, p));
        }
    };
    path("vehicle", vehicle);
    path("estimator", estimator);
    path("reference", reference);
    path("calibration", calibration);
    for (name, text) in crate::convert::settings(vehicle_settings)? {
        argv.push("--set".into());
        argv.push(format!("vehicle.{name}={text}").into());
    }
    for r in recordings.unwrap_or_default() {
        argv.push(with("recordings", r));
    }
    list(&mut argv, "speeds", speeds);
    list(&mut argv, "kalker-scales", kalker_scales);
    list(&mut argv, "conicities", conicities);
    list(&mut argv, "lags", lags);
    let seeds = |v: Option<Vec<u32>>| v.map(|v| v.into_iter().map(f64::from).collect());
    list(&mut argv, "validation-seeds", seeds(validation_seeds));
    list(&mut argv, "evaluation-seeds", seeds(evaluation_seeds));
    if let Some(s) = seed {
        argv.extend(["--seed".into(), s.to_string().into()]);
    }
    if let Some(s) = validation_share {
        argv.extend(["--validation-share".into(), s.to_string().into()]);
    }
    if !roll_rate {
        argv.push("--no-roll-rate".into());
    }
    let command = FitArgs::augment_args(clap::Command::new("fit"));
    let matches = command
        .try_get_matches_from(argv)
        .map_err(|e| PyValueError::new_err(e.to_string()))?;
    let args =
        FitArgs::from_arg_matches(&matches).map_err(|e| PyValueError::new_err(e.to_string()))?;
    // The error as its exit code and message: a small value to carry out of the GIL-free part.
    py.detach(|| execute(&args, &|_| {}).map_err(|e| (e.exit_code(), e.to_string())))
        .map_err(|(code, message)| match code {
            2 => PyValueError::new_err(message),
            _ => PyRuntimeError::new_err(message),
        })
}
