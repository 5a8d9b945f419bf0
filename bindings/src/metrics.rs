//! The EN 13848 band metrics of the studies (the same function `alignment-studies` reports
//! with).

use crate::convert::{bad, slice};
use alignment_studies::study::metrics::{self, BANDS, Band};
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArrayLike1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// Jrel, J and the truth's rms per band (whole 3-200 m, D1, D2, D3) of `estimate` against
/// `truth`, each against its own distance signal: `{band: {"J_mm", "Jrel", "truth_rms_mm"}}`.
#[pyfunction]
#[pyo3(signature = (estimate_distance, estimate, truth_distance, truth, *, ds=0.05, trim=10.0))]
pub fn band_metrics<'py>(
    py: Python<'py>,
    estimate_distance: PyArrayLike1<'py, f64, AllowTypeChange>,
    estimate: PyArrayLike1<'py, f64, AllowTypeChange>,
    truth_distance: PyArrayLike1<'py, f64, AllowTypeChange>,
    truth: PyArrayLike1<'py, f64, AllowTypeChange>,
    ds: f64,
    trim: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let (ed, e) = (slice(&estimate_distance), slice(&estimate));
    let (td, t) = (slice(&truth_distance), slice(&truth));
    let (ed, e, td, t) = (&*ed, &*e, &*td, &*t);
    for (what, a, b) in [("estimate", ed, e), ("truth", td, t)] {
        if a.len() != b.len() {
            return Err(bad(format!(
                "{what} has {} samples but its distance {}",
                b.len(),
                a.len()
            )));
        }
    }
    if !(ds > 0.0 && ds.is_finite() && trim >= 0.0 && trim.is_finite()) {
        return Err(bad(format!(
            "ds = {ds} must be positive and trim = {trim} not negative"
        )));
    }
    let m = py
        .detach(|| metrics::evaluate(ed, e, td, t, ds, trim))
        .map_err(bad)?;
    let d = PyDict::new(py);
    for b in BANDS {
        let a = m.get(b.name).expect("every band is evaluated");
        let row = PyDict::new(py);
        row.set_item("J_mm", a.j_mm)?;
        row.set_item("Jrel", a.jrel)?;
        row.set_item("truth_rms_mm", a.truth_rms_mm)?;
        d.set_item(b.name, row)?;
    }
    Ok(d)
}

/// `x` sampled every `ds` metres, band-passed between wavelengths `short` and `long` metres by
/// the metrics' zero-phase Butterworth filter (order 4, forward and backward).
#[pyfunction]
#[pyo3(signature = (x, ds, short, long))]
pub fn bandpass<'py>(
    py: Python<'py>,
    x: PyArrayLike1<'py, f64, AllowTypeChange>,
    ds: f64,
    short: f64,
    long: f64,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    if !(ds > 0.0 && short > 2.0 * ds && long > short && long.is_finite()) {
        return Err(bad(format!(
            "band {short}-{long} m at ds = {ds} m: need 2 ds < short < long"
        )));
    }
    let x = slice(&x);
    let band = Band {
        name: "band",
        short,
        long,
    };
    let y = py
        .detach(|| metrics::bandpass(&x, ds, &band))
        .map_err(bad)?;
    Ok(y.into_pyarray(py))
}

/// The metric's bands as `{name: (shortest, longest wavelength in m)}`, in the studies' order
/// (whole, D1, D2, D3): Python reads the edges from here instead of retyping them.
pub fn bands() -> Vec<(&'static str, (f64, f64))> {
    BANDS.iter().map(|b| (b.name, (b.short, b.long))).collect()
}
