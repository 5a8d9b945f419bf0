//! The hybrid: the learned estimate for the short waves, a Kalman estimate for the long ones,
//! through a complementary split (module docs of [`super`], step 5 and "On board").

use crate::Error;
use crate::study::metrics::{butter, filtfilt};
use sci_rs::signal::filter::design::FilterBandType;
use sci_rs::signal::filter::sosfilt_dyn;

/// Zero-phase high-pass of a signal on a grid of step `ds` \[m\], cut-off wavelength `split` \[m\].
pub fn highpass(x: &[f64], ds: f64, split: f64) -> Result<Vec<f64>, Error> {
    let sos = butter(4, vec![1.0 / split], FilterBandType::Highpass, 1.0 / ds)?;
    Ok(filtfilt(x, &sos, "hybrid's high-pass")?)
}

/// The hybrid estimate `kalman + HP(learned - kalman)` (module docs, step 5).
pub fn hybrid(learned: &[f64], kalman: &[f64], ds: f64, split: f64) -> Result<Vec<f64>, Error> {
    let d: Vec<f64> = learned.iter().zip(kalman).map(|(a, b)| a - b).collect();
    let hp = highpass(&d, ds, split)?;
    Ok(kalman.iter().zip(hp).map(|(k, h)| k + h).collect())
}

/// The hybrid for on-board use: `kalman + HP(learned - kalman)` with a causal Butterworth
/// high-pass of order 2 (its complement `1 - HP` is causal too, so the sum stays exact when both
/// estimates are; the Kalman filter's short-wave error leaks through `1 - HP`, which falls only
/// as `1 / frequency` above the split).
pub fn causal_hybrid(
    learned: &[f64],
    kalman: &[f64],
    ds: f64,
    split: f64,
) -> Result<Vec<f64>, Error> {
    let mut sos = butter(2, vec![1.0 / split], FilterBandType::Highpass, 1.0 / ds)?;
    let d: Vec<f64> = learned.iter().zip(kalman).map(|(a, b)| a - b).collect();
    let hp = sosfilt_dyn(d.iter(), &mut sos);
    Ok(kalman.iter().zip(hp).map(|(k, h)| k + h).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::learned::synthetic::rms;

    #[test]
    fn the_hybrid_takes_short_waves_from_one_and_long_waves_from_the_other() {
        let n = 2000;
        let wave =
            |l: f64, a: f64| (0..n).map(move |i| a * (std::f64::consts::TAU * i as f64 / l).sin());
        let short: Vec<f64> = wave(8.0, 1.0).collect();
        let long: Vec<f64> = wave(200.0, 1.0).collect();
        // `learned` is right on the short wave, wrong on the long one; `kalman` the reverse.
        let learned: Vec<f64> = short
            .iter()
            .zip(wave(200.0, -0.5))
            .map(|(a, b)| a + b)
            .collect();
        let kalman: Vec<f64> = long
            .iter()
            .zip(wave(8.0, 0.3))
            .map(|(a, b)| a + b)
            .collect();
        let h = hybrid(&learned, &kalman, 1.0, 40.0).unwrap();
        let err: Vec<f64> = (200..n - 200).map(|i| h[i] - short[i] - long[i]).collect();
        assert!(rms(&err) < 0.02, "{}", rms(&err));
        // Equal inputs come back unchanged.
        assert_eq!(hybrid(&kalman, &kalman, 1.0, 40.0).unwrap(), kalman);
        // The causal split, less sharply. The error is -HP(long - learned's long) - (1 - HP)
        // (short - kalman's short) = -1.5 HP(long) - 0.7 (1 - HP)(short); for the order-2
        // Butterworth at x = f / f_c, |HP| = x^2 / |1 - x^2 + i sqrt(2) x| = 0.040 at x = 0.2 and
        // |1 - HP| = |1 + i sqrt(2) x| / |1 - x^2 + i sqrt(2) x| = 0.285 at x = 5: amplitudes
        // 0.060 and 0.200, rms sqrt((0.060^2 + 0.200^2) / 2) = 0.148 (analytic).
        let c = causal_hybrid(&learned, &kalman, 1.0, 40.0).unwrap();
        let err: Vec<f64> = (600..n).map(|i| c[i] - short[i] - long[i]).collect();
        assert!((rms(&err) - 0.148).abs() < 0.01, "{}", rms(&err));
        assert_eq!(causal_hybrid(&kalman, &kalman, 1.0, 40.0).unwrap(), kalman);
    }
}
