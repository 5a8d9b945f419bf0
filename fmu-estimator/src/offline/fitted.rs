//! Samples told the design fitted from their own sensors (`design_line::fit`): the offline
//! mode for a curved line whose design is not known, shared by `alignment-studies smooth
//! --fit-design` and the studies' curve table.

use super::Sample;
use crate::design::DesignModel;
use design_line::fit::{self, Fitted, Record};

/// `samples` (taken every `h` seconds) with `design` replaced by the line fitted from their
/// roll and yaw gyroscopes and axle-box accelerometer, rounded as the line's default, with the
/// gauge and gravity of the vehicle's design-response `model`; and the fit.
pub fn with_fitted_design(
    samples: &[Sample],
    h: f64,
    model: &DesignModel,
) -> Result<(Vec<Sample>, Fitted), String> {
    let column = |f: fn(&Sample) -> f64| -> Vec<f64> { samples.iter().map(f).collect() };
    let (speed, yaw, roll, acc) = (
        column(|s| s.speed),
        column(|s| s.ws_yaw_rate),
        column(|s| s.ws_roll_rate),
        column(|s| s.ws_acc_y),
    );
    let record = Record {
        step: h,
        speed: &speed,
        yaw_rate: &yaw,
        roll_rate: &roll,
        acc_y: &acc,
    };
    let rounding = design_line::DEFAULT_ROUNDING;
    let fitted = fit::fit(&record, model.half_gauge, model.gravity, rounding)?;
    let (_, design) = fitted.at_samples(&record, rounding)?;
    let mut out = samples.to_vec();
    for (s, d) in out.iter_mut().zip(design) {
        s.design = d;
    }
    Ok((out, fitted))
}
