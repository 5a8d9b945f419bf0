//! The lateral-alignment estimator of Muñoz, Ros & Escalona ("Estimation of lateral track
//! irregularity through Kalman filtering techniques", docs/references.md), as an FMI 2.0
//! co-simulation FMU.
//!
//! The default estimator (`estimator = 2`) is the learned filter: the paper's Kalman filter
//! runs as one of its channels, and a multichannel FIR over the sensors, fitted in the metric's
//! bands, gives the estimate. One sample's path through the FMU, in call order:
//!
//! | step | module |
//! |---|---|
//! | the FMI call, the variable table, what each FMI phase does | [`fmu`], [`variables`] |
//! | the user's settings, read once at initialization | [`config`], [`calibration`] |
//! | the files it reads (tap bank, design response), parsed once per process and shared | [`parsed`] |
//! | one sample's step, the same in the FMU and offline: distance, hold, sensors, filters | [`step`] |
//! | a sample refused or skipped (NaN, out of range, standstill) | [`plausible`] |
//! | the design line's response removed from the sensors | [`design`] |
//! | the sensors' biases, found at a standstill; their integrals in motion, which flag a curve or a bias the estimator was not told of | [`bias`], [`integrals`] |
//! | the Kalman filter's step (matrices at the current speed, predict, update) | [`core`], [`engine`], [`filter`] |
//! | the learned filter: its tap bank and the bank's contract (checked at initialization), grid, history, windows, speed and contact blending, fixed lag | [`learned`] |
//!
//! The paper's filter, which the learned one builds on and which `estimator = 1` runs alone:
//!
//! | concern | module |
//! |---|---|
//! | the simplified model's parameters (Table 2) and their sources | [`params`] |
//! | the simplified model, its derivation and sign conventions, `F_c` and `H` | [`model`] |
//! | the filter's linear system for an alignment prior, re-evaluated at every speed | [`statespace`], [`prior`] |
//! | the paper's second-order discretization and the exact one | [`discretize`] |
//! | the PBH observability test run at initialization | [`observability`] |
//!
//! Offline (recordings, the studies, the Python bindings): [`offline`] runs the same steps over a
//! whole record, and [`smoother`] adds the Rauch-Tung-Striebel smoother.
//!
//! Errors are typed by concern in [`error`] (a refused setting, a calibration file, the gain, a
//! sample); the FMU logs their message with fmi2Error.
//!
//! The FMU's variables are listed in `documentation/index.html` inside the packaged FMU and in
//! `docs/estimator-fmu.md`.

// `!(x > 0.0)` is how we reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod bias;
pub mod calibration;
pub mod config;
pub mod core;
pub mod design;
pub mod discretize;
pub mod engine;
pub mod error;
pub mod filter;
pub mod fmu;
pub mod integrals;
pub mod learned;
pub mod model;
pub mod observability;
pub mod offline;
pub mod params;
pub mod parsed;
pub mod plausible;
pub mod prior;
pub mod smoother;
pub mod statespace;
pub mod step;
pub mod variables;

pub use fmu::Estimator;

/// The method, for documentation/index.html.
pub const METHOD_HTML: &str = include_str!("../doc/method.html");

/// The modelDescription.xml content of this FMU, from its variable table.
pub fn model_description() -> model_description::ModelDescription {
    fmi_abi::description::model_description::<Estimator>()
}
