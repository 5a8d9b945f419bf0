//! `estimate`: the estimator FMU's stepping over whole arrays, with every FMU parameter.

use crate::convert::{bad, slice};
use fmi_abi::variables::Start;
use fmu_estimator::offline::{self, Columns, CovarianceCheck, Processed, Resume};
use fmu_estimator::variables::VARIABLES;
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike1};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// Where a call of `estimate` stopped (returned as `state`): the filters and the distance,
/// with the settings, calibration and step they were made with. Passed as `resume`, the next
/// call continues as if its samples had followed in the same call: a recording longer than
/// memory, or a day-long soak, goes through in pieces.
#[pyclass(module = "track_alignment._native", frozen)]
pub struct EstimatorState {
    resume: Resume,
    /// The settings as `(name, text)`, sorted: a dictionary in another order is the same.
    settings: Vec<(String, String)>,
    calibration: Option<PathBuf>,
    step: f64,
}

/// Estimates the lateral alignment from recorded sensor signals, exactly as the estimator FMU
/// does when stepped every `step` seconds with these samples (bit-equal outputs).
#[pyfunction]
#[pyo3(signature = (speed, ws_acc_y, ws_yaw_rate, frame_acc_y, *, step, ws_roll_rate=None, design_curvature=None, design_cant=None, settings=None, calibration=None, smooth=false, check_covariance=false, resume=None))]
#[allow(clippy::too_many_arguments)]
pub fn estimate<'py>(
    py: Python<'py>,
    speed: PyArrayLike1<'py, f64, AllowTypeChange>,
    ws_acc_y: PyArrayLike1<'py, f64, AllowTypeChange>,
    ws_yaw_rate: PyArrayLike1<'py, f64, AllowTypeChange>,
    frame_acc_y: PyArrayLike1<'py, f64, AllowTypeChange>,
    step: f64,
    ws_roll_rate: Option<PyArrayLike1<'py, f64, AllowTypeChange>>,
    design_curvature: Option<PyArrayLike1<'py, f64, AllowTypeChange>>,
    design_cant: Option<PyArrayLike1<'py, f64, AllowTypeChange>>,
    settings: Option<&Bound<'py, PyDict>>,
    calibration: Option<PathBuf>,
    smooth: bool,
    check_covariance: bool,
    resume: Option<PyRef<'py, EstimatorState>>,
) -> PyResult<Bound<'py, PyDict>> {
    let overrides = crate::convert::settings(settings)?;
    let mut sorted = overrides.clone();
    sorted.sort();
    let start = match &resume {
        None => None,
        Some(_) if smooth => {
            return Err(bad(
                "smooth=True cannot resume a state: the smoother needs the run from its first sample",
            ));
        }
        Some(r) if r.settings != sorted || r.calibration != calibration || r.step != step => {
            return Err(bad(format!(
                "resume: the state was made with settings {:?}, calibration {:?} and step {} s; this call has {:?}, {:?} and {} s",
                r.settings, r.calibration, r.step, sorted, calibration, step
            )));
        }
        Some(r) => Some(r.resume.clone()),
    };
    let (v, a, y, f) = (
        slice(&speed),
        slice(&ws_acc_y),
        slice(&ws_yaw_rate),
        slice(&frame_acc_y),
    );
    let roll = ws_roll_rate.as_ref().map(|r| slice(r));
    let (curvature, cant) = match (&design_curvature, &design_cant) {
        (Some(k), Some(c)) => (Some(slice(k)), Some(slice(c))),
        (None, None) => (None, None),
        _ => {
            return Err(bad(
                "design_curvature and design_cant come together: give both arrays, or neither (straight, level track)",
            ));
        }
    };
    let columns = Columns {
        speed: &v,
        ws_acc_y: &a,
        ws_yaw_rate: &y,
        frame_acc_y: &f,
        ws_roll_rate: roll.as_deref(),
        design: curvature.as_deref().zip(cant.as_deref()),
    };
    let how = How {
        smooth,
        check: check_covariance,
        start,
    };
    let (mut out, lag, end) = py
        .detach(|| run(&overrides, calibration.as_deref(), step, &columns, how))
        .map_err(bad)?;
    let covariance = out.covariance.take();
    let d = outputs(py, out, lag)?;
    if let Some(c) = covariance {
        d.set_item("covariance", covariance_dict(py, &c)?)?;
    }
    if let Some(resume) = end {
        let state = EstimatorState {
            resume,
            settings: sorted,
            calibration,
            step,
        };
        d.set_item("state", Py::new(py, state)?)?;
    }
    Ok(d)
}

/// How `estimate` runs: with the smoother, checking the covariance, from a saved state.
struct How {
    smooth: bool,
    check: bool,
    start: Option<Resume>,
}

/// The covariance check as a dictionary of its fields.
fn covariance_dict<'py>(py: Python<'py>, c: &CovarianceCheck) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("steps", c.steps)?;
    d.set_item("not_positive_definite", c.not_positive_definite)?;
    d.set_item("eigen_steps", c.eigen_steps)?;
    d.set_item("min_eigenvalue", c.min_eigenvalue)?;
    d.set_item("min_relative", c.min_relative)?;
    d.set_item("max_asymmetry", c.max_asymmetry)?;
    Ok(d)
}

/// The FMU's configuration and learned filter for `overrides`, run over `columns`; also the
/// learned filter's lag (for `distance_lagged`) and, without the smoother, where the run
/// stopped.
fn run(
    overrides: &[(String, String)],
    calibration: Option<&std::path::Path>,
    step: f64,
    columns: &Columns,
    how: How,
) -> Result<(Processed, f64, Option<Resume>), fmu_estimator::error::Error> {
    let values = offline::settings(overrides)?;
    let (config, _notes) = offline::config(&values, calibration)?;
    offline::one_design(&config, columns.design.is_some())?;
    let learned = offline::learned(&values, &config)?;
    let lag = learned.as_ref().map_or(0.0, |l| l.lag());
    if how.smooth {
        let out = if how.check {
            offline::process_columns_checked(&config, learned, step, columns, true)?
        } else {
            offline::process_columns(&config, learned, step, columns, true)?
        };
        return Ok((out, lag, None));
    }
    let start = how.start.unwrap_or_else(|| Resume::new(&config, learned));
    let (out, end) = offline::process_columns_from(&config, start, step, columns, how.check)?;
    Ok((out, lag, Some(end)))
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
            // The FMU's alignment_std of the paper's filter: grown by the integrals' check.
            let std: Vec<f64> = kalman_std
                .iter()
                .zip(&out.changes)
                .map(|(s, c)| s * fmu_estimator::integrals::growth(*c))
                .collect();
            d.set_item("alignment", kalman.clone().into_pyarray(py))?;
            d.set_item("alignment_std", std.clone().into_pyarray(py))?;
            d.set_item("alignment_lagged", kalman.clone().into_pyarray(py))?;
            d.set_item("alignment_lagged_std", std.into_pyarray(py))?;
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
    d.set_item(
        "conicity_estimate",
        out.conicity
            .unwrap_or_else(|| vec![0.0; n])
            .into_pyarray(py),
    )?;
    let novelty = out.novelty.unwrap_or_else(|| vec![0.0; n]);
    d.set_item("novelty", novelty.into_pyarray(py))?;
    d.set_item("outside_training", out.outside_training.into_pyarray(py))?;
    for (i, name) in [
        "heading_change",
        "relative_velocity_change",
        "heading_level",
    ]
    .into_iter()
    .enumerate()
    {
        let column: Vec<f64> = out.changes.iter().map(|c| c[i]).collect();
        d.set_item(name, column.into_pyarray(py))?;
    }
    let bias = out.bias.unwrap_or_else(|| vec![[0.0; 4]; n]);
    for (i, name) in [
        "ws_acc_y_bias",
        "ws_yaw_rate_bias",
        "frame_acc_y_bias",
        "ws_roll_rate_bias",
    ]
    .into_iter()
    .enumerate()
    {
        let column: Vec<f64> = bias.iter().map(|b| b[i]).collect();
        d.set_item(name, column.into_pyarray(py))?;
    }
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
