//! Python values to the library's terms: settings dictionaries become the `(name, text)` pairs
//! the CLI's `--set` gives (so the FMU's own parsing and error messages apply), arrays become
//! slices without a copy.

use numpy::PyReadonlyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyString};
use std::borrow::Cow;

/// `{name: value}` as `(name, text)`; a bool is `true`/`false`, a float its shortest exact
/// decimal form (Rust's `Display`, which parses back to the same `f64`).
pub fn settings(dict: Option<&Bound<'_, PyDict>>) -> PyResult<Vec<(String, String)>> {
    let Some(dict) = dict else { return Ok(vec![]) };
    let mut out = Vec::with_capacity(dict.len());
    for (k, v) in dict.iter() {
        let name: String = k
            .extract()
            .map_err(|_| PyValueError::new_err(format!("setting name {k} is not a string")))?;
        let text = if v.is_instance_of::<PyBool>() {
            v.extract::<bool>()?.to_string()
        } else if v.is_instance_of::<PyInt>() {
            v.extract::<i64>()?.to_string()
        } else if v.is_instance_of::<PyFloat>() {
            v.extract::<f64>()?.to_string()
        } else if v.is_instance_of::<PyString>() {
            v.extract::<String>()?
        } else {
            // numpy scalars and other numbers: their float value.
            match v.extract::<f64>() {
                Ok(x) => x.to_string(),
                Err(_) => {
                    return Err(PyValueError::new_err(format!(
                        "setting '{name}': {} is not a bool, number or string",
                        v.get_type().name()?
                    )));
                }
            }
        };
        out.push((name, text));
    }
    Ok(out)
}

/// The array's memory as a slice when it is contiguous (read in place, the usual case: numpy
/// arrays and pandas columns); a strided view (a column of a 2-D array) is copied once.
pub fn slice<'a>(a: &'a PyReadonlyArray1<'_, f64>) -> Cow<'a, [f64]> {
    match a.as_slice() {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => Cow::Owned(a.as_array().iter().copied().collect()),
    }
}

/// A library error for bad input.
pub fn bad(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}
