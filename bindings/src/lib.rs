//! Python bindings of the toolkit (issue 16): the estimator over numpy arrays, the EN 13848
//! band metrics and vehicle-FMU runs, as the module `track_alignment._native`.
//!
//! | Python | Rust it calls | equal to |
//! |---|---|---|
//! | `estimate` | `fmu_estimator::offline::process_columns` | the estimator FMU's outputs, bit for bit |
//! | `band_metrics`, `bandpass` | the studies' `metrics::evaluate`, `metrics::bandpass` | `alignment-studies` figures |
//! | `BANDS` | the studies' `metrics::BANDS` | the band edges every report uses |
//! | `simulate` | the co-simulation master, one FMU | `orchestrator simulate` of that FMU |
//! | `fit` | `alignment_studies::cli::fit` with the command's own parser | `alignment-studies fit` |
//! | `fit_design` | `design_line::fit` | the design line of a record whose design is not known |
//!
//! Why a thin layer: every number comes from the same code the FMU and the CLI run, so the
//! bindings add conversions and nothing else. Input arrays are read where numpy holds them (no
//! copy) and the GIL is released while Rust computes, so Dask threads run in parallel. Errors
//! carry the library's messages: `ValueError` for bad input, `RuntimeError` for a run that
//! failed.

mod convert;
mod design;
mod estimate;
mod fit;
mod metrics;
mod simulate;

use pyo3::prelude::*;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(estimate::estimate, m)?)?;
    m.add_function(wrap_pyfunction!(estimate::parameters, m)?)?;
    m.add_class::<estimate::EstimatorState>()?;
    m.add_function(wrap_pyfunction!(metrics::band_metrics, m)?)?;
    m.add_function(wrap_pyfunction!(metrics::bandpass, m)?)?;
    m.add_function(wrap_pyfunction!(simulate::simulate, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(design::fit_design, m)?)?;
    m.add("BANDS", metrics::bands())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
