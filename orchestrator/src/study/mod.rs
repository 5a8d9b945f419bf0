//! The estimation studies of the paper: accuracy metrics in the EN 13848 bands (more to come:
//! identification, calibration, robustness and resonance cases).

pub mod metrics;
pub mod standard;
