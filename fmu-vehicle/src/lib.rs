//! A metro vehicle on an irregular straight or curved track, with virtual inertial sensors, as an FMI 2.0
//! co-simulation FMU: the "complete model" against which the alignment estimator is judged.
//!
//! - [`params`]: vehicle parameter sets (ML95-like metro car, Manchester Benchmark vehicle) with
//!   the source of every value;
//! - [`track`]: track irregularities (spectra, harmonic, measured profiles);
//! - [`mod@line`] (the `design-line` crate): the design line (curvature and cant) the irregularities are laid on;
//! - [`curving`]: what a curved, canted line adds to the equations and sensors;
//! - [`contact`]: Hertz contact, Kalker creep coefficients, saturation, flange;
//! - [`dynamics`]: the equations of motion and their derivation;
//! - [`simulation`]: time integration, run-in, virtual sensors and noise;
//! - [`modal`]: linearization, natural frequencies, critical speed;
//! - [`fmu`]: the FMI variable table and phases.

// `!(x > 0.0)` is how we reject NaN together with the out-of-range values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod contact;
pub mod curving;
pub mod dynamics;
pub mod fmu;
/// The design line, in its own crate so that the estimator FMU reads the same line files.
pub use design_line as line;
pub mod modal;
pub mod params;
pub mod sensors;
pub mod simulation;
pub mod track;

pub use fmu::RailVehicle;

/// The method, for documentation/index.html.
pub const METHOD_HTML: &str = include_str!("../doc/method.html");

/// The modelDescription.xml content of this FMU, from its variable table.
pub fn model_description() -> model_description::ModelDescription {
    fmi_abi::description::model_description::<RailVehicle>()
}
