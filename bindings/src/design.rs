//! The design line fitted from the sensors (`design_line::fit`), for a record whose design is
//! not known: the arrays the estimator then takes as `design_curvature` and `design_cant`.

use crate::convert::{bad, slice};
use design_line::fit::{self, Record};
use fmu_estimator::offline;
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

/// The design line of a record fitted from its wheelset roll and yaw gyroscopes and axle-box
/// accelerometer: `{"design_curvature", "design_cant", "distance"}` per sample (at the
/// estimator's distance, `speed * step` per sample), `"rows"` (distance, curvature, cant: a line
/// file's rows) and `"transitions"` (start, end, curvature and cant change). `half_gauge` and
/// `gravity` default to those of the design-response model `design_response_file` names (the
/// estimator's parameter: the shipped model's name or a file), the ML95's when not given.
#[pyfunction]
#[pyo3(signature = (speed, ws_yaw_rate, ws_roll_rate, ws_acc_y, *, step, rounding=design_line::DEFAULT_ROUNDING, half_gauge=None, gravity=None, design_response_file=None))]
#[allow(clippy::too_many_arguments)]
pub fn fit_design<'py>(
    py: Python<'py>,
    speed: PyArrayLike1<'py, f64, AllowTypeChange>,
    ws_yaw_rate: PyArrayLike1<'py, f64, AllowTypeChange>,
    ws_roll_rate: PyArrayLike1<'py, f64, AllowTypeChange>,
    ws_acc_y: PyArrayLike1<'py, f64, AllowTypeChange>,
    step: f64,
    rounding: f64,
    half_gauge: Option<f64>,
    gravity: Option<f64>,
    design_response_file: Option<String>,
) -> PyResult<Bound<'py, PyDict>> {
    let (half_gauge, gravity) = match (half_gauge, gravity) {
        (Some(l), Some(g)) => (l, g),
        _ => {
            // The model the estimator itself would read for that setting (its look-up and
            // messages), not a second resolution of the name.
            let overrides: Vec<(String, String)> = design_response_file
                .map(|f| vec![("design_response_file".to_string(), f)])
                .unwrap_or_default();
            let values = offline::settings(&overrides).map_err(bad)?;
            let (config, _) = offline::config(&values, None).map_err(bad)?;
            let m = config.design.ok_or_else(|| {
                bad("design_response_file is empty: the fit needs the vehicle's gauge and gravity from a design-response model (or half_gauge and gravity)")
            })?;
            (
                half_gauge.unwrap_or(m.half_gauge),
                gravity.unwrap_or(m.gravity),
            )
        }
    };
    let (v, wz, wx, a) = (
        slice(&speed),
        slice(&ws_yaw_rate),
        slice(&ws_roll_rate),
        slice(&ws_acc_y),
    );
    let record = Record {
        step,
        speed: &v,
        yaw_rate: &wz,
        roll_rate: &wx,
        acc_y: &a,
    };
    let (fitted, distance, design) = py
        .detach(|| -> Result<_, String> {
            let fitted = fit::fit(&record, half_gauge, gravity, rounding)?;
            let (distance, design) = fitted.at_samples(&record, rounding)?;
            Ok((fitted, distance, design))
        })
        .map_err(bad)?;
    let (k, c): (Vec<f64>, Vec<f64>) = design.iter().map(|d| (d[0], d[1])).unzip();
    let out = PyDict::new(py);
    out.set_item("design_curvature", k.into_pyarray(py))?;
    out.set_item("design_cant", c.into_pyarray(py))?;
    out.set_item("distance", distance.into_pyarray(py))?;
    out.set_item("rows", fitted.rows())?;
    let transitions = PyList::empty(py);
    for t in &fitted.transitions {
        let d = PyDict::new(py);
        d.set_item("start", t.start)?;
        d.set_item("end", t.end)?;
        d.set_item("curvature", t.curvature)?;
        d.set_item("cant", t.cant)?;
        transitions.append(d)?;
    }
    out.set_item("transitions", transitions)?;
    Ok(out)
}
