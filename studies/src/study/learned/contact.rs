//! The contact model of a tap bank: the Kalker-coefficient scale as a linear function of the
//! contact features ([`fmu_estimator::learned::contact`]), fitted by least squares on the
//! training runs of every trained condition at one speed, its error measured on the validation
//! runs.
//!
//! The features come from the estimator's own [`Moments`] over each run's grid cells, so the fit
//! sees exactly what the FMU computes. The first [`WARM_UP`] of a run (the moments' memory
//! filling, and the start transient) is left out of the fit and of the error.

use super::taps::{BANK_GRID, CONTACT_BAND, CONTACT_MEMORY, GridRun};
use crate::Error;
use fmu_estimator::learned::contact::{FEATURES, Moments, SpeedModel};
use nalgebra::{DMatrix, DVector};

/// Start of each run left out \[m\].
pub const WARM_UP: f64 = CONTACT_MEMORY;

/// The features of every cell of a run at `speed` past the warm-up.
fn features(run: &GridRun, speed: f64) -> Vec<[f64; FEATURES]> {
    let mut m = Moments::new(BANK_GRID, CONTACT_BAND, CONTACT_MEMORY, &[speed]);
    let skip = (WARM_UP / BANK_GRID).round() as usize;
    let mut out = vec![];
    for (i, cell) in run.cells.cells.iter().enumerate() {
        m.push(cell, speed);
        if i >= skip
            && let Some(f) = m.features(0)
        {
            out.push(f);
        }
    }
    out
}

/// The model at `speed` from runs labelled by their Kalker scale.
pub(super) fn fit(
    speed: f64,
    training: &[(f64, GridRun)],
    validation: &[(f64, GridRun)],
) -> Result<SpeedModel, Error> {
    let n = FEATURES + 1;
    let (mut ata, mut aty) = (DMatrix::<f64>::zeros(n, n), DVector::<f64>::zeros(n));
    for (k, r) in training {
        for f in features(r, speed) {
            let a = DVector::from_iterator(n, f.iter().copied().chain([1.0]));
            ata += &a * a.transpose();
            aty += &a * *k;
        }
    }
    let coefficients = ata
        .cholesky()
        .ok_or_else(|| {
            Error::input(format!(
                "at {speed} m/s the contact features do not tell the conditions apart"
            ))
        })?
        .solve(&aty);
    let coefficients: Vec<f64> = coefficients.iter().copied().collect();
    let (mut sq, mut count) = (0.0, 0usize);
    for (k, r) in validation {
        for f in features(r, speed) {
            let e: f64 = f.iter().zip(&coefficients).map(|(x, c)| x * c).sum::<f64>()
                + coefficients[FEATURES]
                - k;
            sq += e * e;
            count += 1;
        }
    }
    Ok(SpeedModel {
        speed,
        coefficients,
        rms_error: (sq / count.max(1) as f64).sqrt(),
    })
}
