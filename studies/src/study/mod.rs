//! The estimation studies of the paper: accuracy metrics in the EN 13848 bands, identification
//! of the simplified model, calibration of the filter, and the evaluation cases.

pub mod calibrate;
pub mod cases;
pub mod curves;
pub mod design;
pub mod identify;
pub mod interface;
pub mod learned;
pub mod metrics;
pub mod optimize;
pub mod plot;
pub mod records;
pub mod runs;
pub mod sensors;
pub mod standard;
pub mod standard_case;
pub mod variants;
pub mod vehicles;
