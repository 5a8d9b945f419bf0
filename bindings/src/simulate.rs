//! `simulate`: one FMU (the vehicle, typically) run by the co-simulation master, its recorded
//! variables returned as arrays rather than written to results.csv.

use crate::convert::{bad, settings};
use fmi_import::{LogConfig, fmi2Status};
use numpy::IntoPyArray;
use orchestrator::master::{Cosimulation, RunOptions};
use orchestrator::system::{Component, Endpoint, Experiment, System, Value};
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Runs the FMU at `fmu` from 0 to `stop_time` with communication step `step`, after applying
/// `parameters` (`{name: value}`, as `orchestrator simulate --set`), and returns `{"time": ...,
/// variable: ...}` for `variables` (default: every output).
#[pyfunction]
#[pyo3(signature = (fmu, stop_time, *, step=1e-3, parameters=None, variables=None))]
pub fn simulate<'py>(
    py: Python<'py>,
    fmu: PathBuf,
    stop_time: f64,
    step: f64,
    parameters: Option<&Bound<'py, PyDict>>,
    variables: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    const NAME: &str = "fmu";
    let system = System {
        name: NAME.into(),
        components: vec![Component {
            name: NAME.into(),
            source: fmu,
            parameters: settings(parameters)?
                .into_iter()
                .map(|(n, v)| (n, Value::String(v)))
                .collect(),
        }],
        connections: vec![],
        experiment: Experiment::default(),
    };
    let options = RunOptions {
        record: variables.map(|v| v.iter().map(|n| Endpoint::new(NAME, n)).collect()),
        log: fmi_import_log(),
        collect: true,
        ..RunOptions::new(0.0, stop_time, step)
    };
    let table = py.detach(|| {
        let cosim = Cosimulation::load(system).map_err(|e| bad(e.to_string()))?;
        let summary = cosim
            .run(&options)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        summary
            .table
            .ok_or_else(|| PyRuntimeError::new_err("the master collected no table"))
    })?;
    let d = PyDict::new(py);
    let prefix = format!("{NAME}.");
    for (name, data) in table.columns.into_iter().zip(table.data) {
        let key = name.strip_prefix(&prefix).unwrap_or(&name).to_string();
        d.set_item(key, data.into_pyarray(py))?;
    }
    Ok(d)
}

/// Only errors are logged: a Python caller sees them in the exception.
fn fmi_import_log() -> LogConfig {
    LogConfig {
        min_status: fmi2Status::Error,
        ..Default::default()
    }
}
