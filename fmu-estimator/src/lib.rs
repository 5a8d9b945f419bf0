//! The lateral-alignment estimator of Muñoz, Ros & Escalona ("Estimation of lateral track
//! irregularity through Kalman filtering techniques", docs/references.md), as an FMI 2.0
//! co-simulation FMU.
//!
//! - [`params`]: the simplified model's parameters (Table 2) and their sources;
//! - [`model`]: the simplified model, its derivation and sign conventions, `F_c` and `H`;
//! - [`discretize`]: the paper's second-order scheme and the exact one;
//! - [`filter`]: the Kalman filter;
//! - [`observability`]: the PBH test run at initialization;
//! - [`calibration`]: Q and R, from the calibration file or the diagonal model;
//! - [`fmu`]: the FMI variable table and what each FMI phase does.
//!
//! The FMU's variables are listed in `documentation/index.html` inside the packaged FMU and in
//! `docs/estimator-fmu.md`.

// `!(x > 0.0)` is how we reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod calibration;
pub mod config;
pub mod core;
pub mod discretize;
pub mod engine;
pub mod filter;
pub mod fmu;
pub mod learned;
pub mod model;
pub mod observability;
pub mod offline;
pub mod params;
pub mod plausible;
pub mod prior;
pub mod smoother;
pub mod statespace;
pub mod variables;

pub use fmu::Estimator;

/// The method, for documentation/index.html.
pub const METHOD_HTML: &str = include_str!("../doc/method.html");

/// The modelDescription.xml content of this FMU, from its variable table.
pub fn model_description() -> model_description::ModelDescription {
    fmi_abi::description::model_description::<Estimator>()
}
