//! The paper's accuracy indices in the EN 13848 wavelength bands.
//!
//! Procedure (documented because every choice changes the numbers):
//! 1. Estimate and truth are put on one uniform distance grid (`ds`, default 0.05 m) by linear
//!    interpolation, each against its own distance signal: a row of the estimate and a row of
//!    the truth are compared at the same track position, whatever the master's latency.
//! 2. Each is filtered by a zero-phase Butterworth band-pass between the band's wavelengths:
//!    order 4 (8 poles in second-order sections), designed in spatial frequency `1/m` with the
//!    sampling rate `1/ds`, applied forward and backward (`sosfiltfilt`, odd padding, as
//!    scipy's default), as the public UIC 518 implementation does (docs/references.md section 3).
//! 3. The first and last `trim` metres (default 10 m) are dropped, where the forward-backward
//!    filter starts and stops.
//! 4. `J = rms(estimate - truth)` and `Jrel = J / rms(truth)`.
//!
//! Bands: whole 3-200 m, D1 3-25 m, D2 25-70 m, D3 70-200 m.

use sci_rs::signal::filter::design::{
    DigitalFilter, FilterBandType, FilterOutputType, Sos, butter_dyn,
};
use sci_rs::signal::filter::sosfiltfilt_dyn;
use serde::Serialize;

/// An EN 13848 wavelength band the accuracy is measured in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    /// The band's name in reports and JSON: `whole`, `D1`, `D2`, `D3`.
    pub name: &'static str,
    /// Shortest and longest wavelength \[m\].
    pub short: f64,
    /// The longest wavelength \[m\] (see `short`).
    pub long: f64,
}

/// The bands, in the order every table and JSON result lists them: the whole range 3-200 m,
/// then EN 13848's D1, D2 and D3. Python reads them through the bindings' `BANDS`.
pub const BANDS: [Band; 4] = [
    Band {
        name: "whole",
        short: 3.0,
        long: 200.0,
    },
    Band {
        name: "D1",
        short: 3.0,
        long: 25.0,
    },
    Band {
        name: "D2",
        short: 25.0,
        long: 70.0,
    },
    Band {
        name: "D3",
        short: 70.0,
        long: 200.0,
    },
];

impl Band {
    /// "D1 3-25 m": how reports, plots and the tap bank's provenance name the band.
    pub fn label(&self) -> String {
        format!("{} {}-{} m", self.name, self.short, self.long)
    }
}

/// Every band's [`Band::label`], comma-separated: "whole 3-200 m, D1 3-25 m, ...".
pub fn band_labels() -> String {
    BANDS.map(|b| b.label()).join(", ")
}

/// The Butterworth band-pass's order (8 poles: 4 per band edge), applied forward and backward.
pub const ORDER: usize = 4;

/// The paper's accuracy indices in one band.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Accuracy {
    /// rms of the error \[mm\].
    #[serde(rename = "J_mm")]
    pub j_mm: f64,
    /// `J / rms(truth)`: 0 is perfect, 1 is no better than estimating 0.
    #[serde(rename = "Jrel")]
    pub jrel: f64,
    /// rms of the band-passed truth \[mm\].
    pub truth_rms_mm: f64,
}

/// `values` sampled at increasing `distance`, linearly interpolated on `grid`.
pub fn resample(distance: &[f64], values: &[f64], grid: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(grid.len());
    let mut i = 0;
    for &s in grid {
        while i + 2 < distance.len() && distance[i + 1] < s {
            i += 1;
        }
        let (d0, d1) = (distance[i], distance[(i + 1).min(distance.len() - 1)]);
        let (v0, v1) = (values[i], values[(i + 1).min(values.len() - 1)]);
        out.push(if d1 > d0 {
            v0 + (v1 - v0) * ((s - d0) / (d1 - d0)).clamp(0.0, 1.0)
        } else {
            v0
        });
    }
    out
}

/// The uniform grid covering the distances both signals have.
pub fn common_grid(a: &[f64], b: &[f64], ds: f64) -> Vec<f64> {
    let start = a[0].max(b[0]);
    let end = a[a.len() - 1].min(b[b.len() - 1]);
    let n = ((end - start) / ds).floor() as usize + 1;
    (0..n).map(|k| start + k as f64 * ds).collect()
}

/// Why a signal cannot be filtered or evaluated in the metric's bands: the record (or the
/// grid) does not suffice. Bad input to a study (exit 2).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MetricError {
    /// The filter design returned another form than second-order sections (a library fault,
    /// not an input's).
    #[error("the Butterworth design did not return second-order sections")]
    NotSos,
    /// The grid is shorter than the forward-backward filter's padding needs.
    #[error("{samples} samples are too few for the {filter} (at least {needed})")]
    TooShort {
        /// The signal's samples.
        samples: usize,
        /// The filter, e.g. "D1 band-pass".
        filter: String,
        /// The fewest the filter takes.
        needed: usize,
    },
    /// The grid step cannot resolve the band's shortest wavelength (Nyquist: `2 ds`).
    #[error("band {band} needs wavelengths above {} m: the grid step {ds} m is too coarse", 2.0 * ds)]
    CoarseGrid {
        /// The band's name.
        band: &'static str,
        /// The grid step \[m\].
        ds: f64,
    },
    /// The trim at both ends removes the whole record.
    #[error("trimming {trim} m at each end leaves nothing of {length} m")]
    Trim {
        /// The trim at each end \[m\].
        trim: f64,
        /// The record's length on the grid \[m\].
        length: f64,
    },
    /// Estimate or truth has fewer than two samples.
    #[error("not enough samples to evaluate")]
    NotEnoughSamples,
}

/// A Butterworth design in second-order sections (`cutoffs` in the units of `fs`).
pub fn butter(
    order: usize,
    cutoffs: Vec<f64>,
    kind: FilterBandType,
    fs: f64,
) -> Result<Vec<Sos<f64>>, MetricError> {
    match butter_dyn(
        order,
        cutoffs,
        Some(kind),
        Some(false),
        Some(FilterOutputType::Sos),
        Some(fs),
    ) {
        DigitalFilter::Sos(s) => Ok(s.sos),
        _ => Err(MetricError::NotSos),
    }
}

/// Zero-phase filtering (`sosfiltfilt`, odd padding), refusing signals too short for its padding
/// (`sosfiltfilt` would panic); `what` names the filter in the message.
pub fn filtfilt(x: &[f64], sos: &[Sos<f64>], what: &str) -> Result<Vec<f64>, MetricError> {
    // sosfiltfilt pads with 3 (2 sections + 1) samples at each end.
    let needed = 3 * (2 * sos.len() + 1) + 1;
    if x.len() < needed {
        return Err(MetricError::TooShort {
            samples: x.len(),
            filter: what.to_string(),
            needed,
        });
    }
    Ok(sosfiltfilt_dyn(x.iter(), sos))
}

fn sections(band: &Band, ds: f64) -> Result<Vec<Sos<f64>>, MetricError> {
    let fs = 1.0 / ds;
    let (lo, hi) = (1.0 / band.long, 1.0 / band.short);
    if !(hi < fs / 2.0) {
        return Err(MetricError::CoarseGrid {
            band: band.name,
            ds,
        });
    }
    butter(ORDER, vec![lo, hi], FilterBandType::Bandpass, fs)
}

/// Zero-phase band-pass of a signal sampled every `ds` metres.
pub fn bandpass(x: &[f64], ds: f64, band: &Band) -> Result<Vec<f64>, MetricError> {
    filtfilt(x, &sections(band, ds)?, &format!("{} band-pass", band.name))
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

/// J and Jrel of `estimate` against `truth` (both on the grid of step `ds`) in one band.
pub fn accuracy(
    estimate: &[f64],
    truth: &[f64],
    ds: f64,
    band: &Band,
    trim: f64,
) -> Result<Accuracy, MetricError> {
    let (e, t) = (bandpass(estimate, ds, band)?, bandpass(truth, ds, band)?);
    let n = (trim / ds).round() as usize;
    if 2 * n >= e.len() {
        return Err(MetricError::Trim {
            trim,
            length: e.len() as f64 * ds,
        });
    }
    let (e, t) = (&e[n..e.len() - n], &t[n..t.len() - n]);
    let err: Vec<f64> = e.iter().zip(t).map(|(a, b)| a - b).collect();
    let (j, truth_rms) = (rms(&err), rms(t));
    Ok(Accuracy {
        j_mm: j * 1e3,
        jrel: j / truth_rms,
        truth_rms_mm: truth_rms * 1e3,
    })
}

/// All four bands, from estimate and truth each with its own distance signal.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BandMetrics {
    /// 3-200 m.
    pub whole: Accuracy,
    /// D1, 3-25 m.
    #[serde(rename = "D1")]
    pub d1: Accuracy,
    /// D2, 25-70 m.
    #[serde(rename = "D2")]
    pub d2: Accuracy,
    /// D3, 70-200 m.
    #[serde(rename = "D3")]
    pub d3: Accuracy,
}

impl BandMetrics {
    /// The band named as in [`BANDS`] (`whole`, `D1`, `D2`, `D3`); another name gives `None`.
    pub fn get(&self, name: &str) -> Option<&Accuracy> {
        match name {
            "whole" => Some(&self.whole),
            "D1" => Some(&self.d1),
            "D2" => Some(&self.d2),
            "D3" => Some(&self.d3),
            _ => None,
        }
    }
}

/// The accuracy in every band of `estimate` against `truth`, each against its own distance
/// signal \[m\] (increasing, of its values' length), by the module's procedure on a grid of
/// `ds` \[m\] with `trim` \[m\] dropped at each end. The caller checks the lengths match.
pub fn evaluate(
    estimate_distance: &[f64],
    estimate: &[f64],
    truth_distance: &[f64],
    truth: &[f64],
    ds: f64,
    trim: f64,
) -> Result<BandMetrics, MetricError> {
    if estimate.len() < 2 || truth.len() < 2 {
        return Err(MetricError::NotEnoughSamples);
    }
    let grid = common_grid(estimate_distance, truth_distance, ds);
    let e = resample(estimate_distance, estimate, &grid);
    let t = resample(truth_distance, truth, &grid);
    let a = |b: &Band| accuracy(&e, &t, ds, b, trim);
    Ok(BandMetrics {
        whole: a(&BANDS[0])?,
        d1: a(&BANDS[1])?,
        d2: a(&BANDS[2])?,
        d3: a(&BANDS[3])?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The shipped tap banks' provenance and the reports name the bands so (EN 13848-5's D1-D3
    /// and the paper's whole range).
    #[test]
    fn band_labels_are_the_en_13848_wavelength_ranges() {
        assert_eq!(
            band_labels(),
            "whole 3-200 m, D1 3-25 m, D2 25-70 m, D3 70-200 m"
        );
    }

    fn grid(n: usize, ds: f64) -> Vec<f64> {
        (0..n).map(|k| k as f64 * ds).collect()
    }

    #[test]
    fn identical_signals_give_zero() {
        let s = grid(8000, 0.05);
        let x: Vec<f64> = s
            .iter()
            .map(|v| 1e-3 * (v / 7.0).sin() + 5e-4 * (v / 31.0).cos())
            .collect();
        let m = evaluate(&s, &x, &s, &x, 0.05, 10.0).unwrap();
        for b in BANDS {
            assert_eq!(m.get(b.name).unwrap().j_mm, 0.0);
        }
    }

    #[test]
    fn a_10_m_sinusoid_is_kept_by_d1_and_removed_by_d3() {
        let ds = 0.05;
        let sine = |n: usize| -> Vec<f64> {
            grid(n, ds)
                .iter()
                .map(|v| 1e-3 * (2.0 * std::f64::consts::PI * v / 10.0).sin())
                .collect()
        };
        let amplitude_rms = 1e-3 / 2f64.sqrt();
        // 4 km, judged on the middle 2 km: away from the D3 filter's edge transients, whose
        // impulse response spans hundreds of metres.
        let x = sine(80_001);
        let d1 = bandpass(&x, ds, &BANDS[1]).unwrap();
        let d3 = bandpass(&x, ds, &BANDS[3]).unwrap();
        let middle = |y: &[f64]| rms(&y[20_000..60_000]) / amplitude_rms;
        assert!(
            (middle(&d1) - 1.0).abs() < 0.01,
            "D1 keeps it: {}",
            middle(&d1)
        );
        assert!(middle(&d3) < 1e-4, "D3 removes it: {}", middle(&d3));
        // On a 400 m record minus 10 m at each end, the edge transients leave 9 % of the rms,
        // exactly as scipy's butter + sosfiltfilt do (0.08966): the D3 figures of a 400 m run
        // carry that edge effect, as the paper's must have.
        let short = sine(8_001);
        let d3 = bandpass(&short, ds, &BANDS[3]).unwrap();
        let edge = rms(&d3[200..d3.len() - 200]) / amplitude_rms;
        assert!(
            (edge - 0.08966).abs() < 1e-4,
            "edge transients as in scipy: {edge}"
        );
        // A zero estimate has Jrel 1 in D1.
        let zero = vec![0.0; short.len()];
        assert!((accuracy(&zero, &short, ds, &BANDS[1], 10.0).unwrap().jrel - 1.0).abs() < 1e-12);
    }

    #[test]
    fn resampling_is_linear_interpolation() {
        let d = [0.0, 1.0, 3.0];
        let v = [0.0, 10.0, 30.0];
        assert_eq!(
            resample(&d, &v, &[0.0, 0.5, 2.0, 3.0]),
            vec![0.0, 5.0, 20.0, 30.0]
        );
        assert_eq!(
            common_grid(&[0.0, 10.0], &[1.0, 12.0], 2.0),
            vec![1.0, 3.0, 5.0, 7.0, 9.0]
        );
    }

    #[test]
    fn short_signals_are_refused_with_a_message() {
        assert!(
            bandpass(&[0.0; 10], 0.05, &BANDS[0])
                .unwrap_err()
                .to_string()
                .contains("too few")
        );
        assert!(
            bandpass(&[0.0; 1000], 2.0, &BANDS[0])
                .unwrap_err()
                .to_string()
                .contains("too coarse")
        );
    }
}
