//! `estimate`: the estimator FMU's stepping over whole arrays, with every FMU parameter.

use crate::convert::{bad, slice};
use fmi_abi::variables::Start;
use fmu_estimator::offline::{self, Columns, Processed};
use fmu_estimator::variables::VARIABLES;
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Estimates the lateral alignment from recorded sensor signals, exactly as the estimator FMU
/// does when stepped every `step` seconds with these samples (bit-equal outputs).
#[pyfunction]
#[pyo3(signature = (speed, ws_acc_y, ws_yaw_rate, frame_acc_y, *, step, ws_roll_rate=None, settings=None, calibration=None, smooth=false))]
#[allow(clippy::too_many_arguments)]
pub fn estimate<'py>(
    py: Python<'py>,
    speed: PyArrayLike1<'py, f64, AllowTypeChange>,
    ws_acc_y: PyArrayLike1<'py, f64, AllowTypeChange>,
    ws_yaw_rate: PyArrayLike1<'py, f64, AllowTypeChange>,
    frame_acc_y: PyArrayLike1<'py, f64, AllowTypeChange>,
    step: f64,
    ws_roll_rate: Option<PyArrayLike1<'py, f64, AllowTypeChange>>,
    settings: Option<&Bound<'py, PyDict>>,
    calibration: Option<PathBuf>,
    smooth: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let overrides = crate::convert::settings(settings)?;
    let (v, a, y, f) = (
        slice(&speed),
        slice(&ws_acc_y),
        slice(&ws_yaw_rate),
        slice(&frame_acc_y),
    );
    let roll = ws_roll_rate.as_ref().map(|r| slice(r));
    let columns = Columns {
        speed: &v,
        ws_acc_y: &a,
        ws_yaw_rate: &y,
        frame_acc_y: &f,
        ws_roll_rate: roll.as_deref(),
    };
    let (out, lag) = py
        .detach(|| run(&overrides, calibration.as_deref(), step, &columns, smooth))
        .map_err(bad)?;
    outputs(py, out, lag)
}

/// The FMU's configuration and learned filter for `overrides`, run over `columns`; also the
/// learned filter's lag (for `distance_lagged`).
fn run(
    overrides: &[(String, String)],
    calibration: Option<&std::path::Path>,
    step: f64,
    columns: &Columns,
    smooth: bool,
) -> Result<(Processed, f64), String> {
    let values = offline::settings(overrides)?;
    let (config, _notes) = offline::config(&values, calibration)?;
    let learned = offline::learned(&values)?;
    let lag = learned.as_ref().map_or(0.0, |l| l.lag());
    Ok((
        offline::process_columns(&config, learned, step, columns, smooth)?,
        lag,
    ))
}

/// The FMU's output names, as numpy arrays.
fn outputs(py: Python<'_>, out: Processed, lag: f64) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let kalman: Vec<f64> = out.filtered.iter().map(|e| e.0).collect();
    let kalman_std: Vec<f64> = out.filtered.iter().map(|e| e.1).collect();
    let distance_lagged: Vec<f64> = out.distance.iter().map(|s| s - lag).collect();
    match out.learned {
        Some(est) => {
            let col = |f: fn(&fmu_estimator::learned::Estimate) -> f64| -> Vec<f64> {
                est.iter().map(f).collect()
            };
            d.set_item("alignment", col(|e| e.alignment).into_pyarray(py))?;
            d.set_item("alignment_std", col(|e| e.std).into_pyarray(py))?;
            d.set_item("alignment_lagged", col(|e| e.lagged).into_pyarray(py))?;
            d.set_item(
                "alignment_lagged_std",
                col(|e| e.lagged_std).into_pyarray(py),
            )?;
            let active: Vec<i32> = est.iter().map(|e| e.active).collect();
            d.set_item("active_estimator", active.into_pyarray(py))?;
        }
        None => {
            d.set_item("alignment", kalman.clone().into_pyarray(py))?;
            d.set_item("alignment_std", kalman_std.clone().into_pyarray(py))?;
            d.set_item("alignment_lagged", kalman.clone().into_pyarray(py))?;
            d.set_item("alignment_lagged_std", kalman_std.into_pyarray(py))?;
            let active = vec![fmu_estimator::learned::ACTIVE_PAPER; kalman.len()];
            d.set_item("active_estimator", active.into_pyarray(py))?;
        }
    }
    let n = kalman.len();
    d.set_item("alignment_kalman", kalman.into_pyarray(py))?;
    d.set_item(
        "contact_scale",
        out.contact_scale
            .unwrap_or_else(|| vec![0.0; n])
            .into_pyarray(py),
    )?;
    d.set_item("distance_lagged", distance_lagged.into_pyarray(py))?;
    d.set_item("distance", out.distance.into_pyarray(py))?;
    if let Some(s) = out.smoothed {
        let (x, sd): (Vec<f64>, Vec<f64>) = s.into_iter().unzip();
        d.set_item("alignment_smoothed", x.into_pyarray(py))?;
        d.set_item("alignment_smoothed_std", sd.into_pyarray(py))?;
    }
    d.set_item("skipped_updates", out.skipped)?;
    Ok(d)
}

/// The estimator's parameters: `{name: (type, default, description)}`, from the FMU's
/// variable table (the defaults include the shipped calibration's).
#[pyfunction]
pub fn parameters(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let values = offline::settings(&[]).map_err(bad)?;
    for v in VARIABLES.iter().filter(|v| v.is_parameter()) {
        let i = v.vr as usize;
        let (kind, default): (&str, Py<PyAny>) = match v.start {
            Start::Real(_) => (
                "Real",
                values.real[i].into_pyobject(py)?.into_any().unbind(),
            ),
            Start::Integer(_) => (
                "Integer",
                values.integer[i].into_pyobject(py)?.into_any().unbind(),
            ),
            Start::Boolean(_) => (
                "Boolean",
                pyo3::types::PyBool::new(py, values.boolean[i])
                    .to_owned()
                    .into_any()
                    .unbind(),
            ),
            Start::String(_) => (
                "String",
                values.string[i]
                    .clone()
                    .into_pyobject(py)?
                    .into_any()
                    .unbind(),
            ),
        };
        d.set_item(v.name, (kind, default, v.description))?;
    }
    Ok(d)
}
