//! What a vehicle FMU must offer to be fitted for (`alignment-studies fit`): checked from its
//! modelDescription.xml before any run, so that a missing variable is named at once instead of
//! failing a run minutes later.
//!
//! | role | variables | causality |
//! |---|---|---|
//! | sensors | `ws_acc_y`, `ws_yaw_rate`, `frame_acc_y` | output |
//! | odometry and truth | `forward_speed`, `distance`, `alignment` | output |
//! | the paper's true states (identification, Q/R calibration, the stability check) | `ws_y`, `ws_yaw`, `frame_y`, `ws_vy`, `ws_yaw_rate_true`, `frame_vy` | output |
//! | the speed the studies drive | `speed` | input |
//! | the track and the sensor noise | `track_seed`, `noise_seed` | parameter |
//! | optional: conditions and the fourth sensor | `kalker_scale`, `conicity` (parameters), `ws_roll_rate` (output) | |

use super::calibrate::{SENSORS, TRUTH};
use crate::Error;
use fmi_import::Fmu;
use model_description::Causality;
use std::path::Path;

/// Outputs the fit reads besides the sensors and the true states.
const ODOMETRY: [&str; 2] = ["forward_speed", "distance"];
/// Parameters the fit sets.
const PARAMETERS: [&str; 2] = ["track_seed", "noise_seed"];

/// What the vehicle FMU offers of the optional part.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interface {
    /// A `kalker_scale` parameter: contact conditions can be fitted.
    pub kalker_scale: bool,
    /// A `conicity` parameter: conicity conditions can be fitted.
    pub conicity: bool,
    /// A `ws_roll_rate` output: the four-sensor taps can be fitted.
    pub roll_rate: bool,
}

/// Whether the FMU at `path` has a parameter `name` (false when it cannot be opened: the run
/// that loads it says why).
pub fn has_parameter(path: &Path, name: &str) -> bool {
    Fmu::open_shared(path).is_ok_and(|fmu| {
        fmu.model_description()
            .variable(name)
            .is_some_and(|v| v.causality == Causality::Parameter)
    })
}

/// The vehicle FMU at `path` checked: an error naming the file and every variable missing or
/// of the wrong causality, else what it offers of the optional part.
pub fn check(path: &Path) -> Result<Interface, Error> {
    let fmu = Fmu::open_shared(path)
        .map_err(|e| Error::Input(format!("vehicle FMU {}: {e}", path.display())))?;
    let md = fmu.model_description();
    let has = |name: &str, causality: Causality| {
        md.variable(name).is_some_and(|v| v.causality == causality)
    };
    let mut missing = vec![];
    for name in SENSORS.iter().chain(&ODOMETRY).chain(&TRUTH) {
        if !has(name, Causality::Output) {
            missing.push(format!("output {name}"));
        }
    }
    if !has("speed", Causality::Input) {
        missing.push("input speed".to_string());
    }
    for name in PARAMETERS {
        if !has(name, Causality::Parameter) {
            missing.push(format!("parameter {name}"));
        }
    }
    if !missing.is_empty() {
        return Err(Error::Input(format!(
            "vehicle FMU {} lacks what a fit needs: {} (docs/studies.md, fit)",
            path.display(),
            missing.join(", ")
        )));
    }
    Ok(Interface {
        kalker_scale: has("kalker_scale", Causality::Parameter),
        conicity: has("conicity", Causality::Parameter),
        roll_rate: has("ws_roll_rate", Causality::Output),
    })
}
